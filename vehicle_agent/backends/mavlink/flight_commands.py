"""The MAVLink backend's flight commands: mode changes and arming, and the record of them.

- Take-off: the flight mode (ArduPilot GUIDED, PX4 OFFBOARD; MAV_CMD_DO_SET_MODE), arm; ArduPilot
  then MAV_CMD_NAV_TAKEOFF (param 7: metres above home), disarmed again (best effort) if refused.
  What the backend checks first is :mod:`~vehicle_agent.backends.mavlink.takeoff_checks`.
- Landing: the autopilot's landing mode (ArduPilot LAND, PX4 AUTO.LAND) where the vehicle is;
  once it is down and disarmed, its ground mode (PX4: Hold) asked for now and then, not awaited.
- E-stop: force-disarm (MAV_CMD_COMPONENT_ARM_DISARM, param 2 21196), best effort.
- Recovery sends nothing: :func:`refuse_recovery` says why a vehicle may not be ``idle`` again.

Every mode or arming change the autopilot accepted is recorded (``FlightCommands.commanded_mode``
and ``commanded_at``): the watchdog takes a change we did not command for the pilot's.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable

from vehicle_agent.backends.base import BackendError
from vehicle_agent.backends.mavlink.commands import CommandChannel
from vehicle_agent.backends.mavlink.errors import CommandRejectedError, LinkLostError
from vehicle_agent.backends.mavlink.state import MAV_LANDED_STATE_ON_GROUND, Flavor, LinkState
from vehicle_agent.backends.mavlink.takeoff_checks import CMD_NAV_TAKEOFF

log = logging.getLogger(__name__)

CMD_DO_SET_MODE, CMD_ARM_DISARM = 176, 400
FORCE_DISARM = 21196.0
GROUND_MODE_ASK_PERIOD_S = 0.5
"""How often in [s] a PX4 disarmed in OFFBOARD is asked to go to Hold (a heartbeat is 1 s)."""
GROUND_MODE_WAIT_S = 3.0
"""How long in [s] a landing waits for the ground mode before the vehicle is idle anyway (its
pre-arm state then says it is not in Hold yet)."""


class FlightCommands:
    """Mode changes and arming of the autopilot of ``state`` (its flavor as ``flavor()`` says,
    which raises while none is known)."""

    def __init__(
        self, state: LinkState, commands: CommandChannel, flavor: Callable[[], Flavor]
    ) -> None:
        self._state = state
        self._commands = commands
        self._flavor = flavor
        self.commanded_mode: int | None = None
        """The custom mode we last set (None: none yet)."""
        self.commanded_at = 0
        """The autopilot's heartbeat count when our last mode or arming change was accepted."""
        self._ground_mode_asked_s = -math.inf
        self._ground_mode_since_s = math.inf  # when we began to ask for it (inf: not asking)

    def heard(self) -> None:
        """Take the autopilot's mode and arming as they are now for what we commanded."""
        self.commanded_at = self._state.heartbeats

    async def set_mode(self, custom_mode: int) -> None:
        """Switch the autopilot to ``custom_mode`` (its flavor's encoding); raise if refused."""
        flavor = self._flavor()
        await self._commands.run(CMD_DO_SET_MODE, *flavor.set_mode_params(custom_mode))
        self.commanded_mode = custom_mode
        self.heard()

    async def arm(self) -> None:
        """Arm; raise :class:`ArmingRefusedError` if refused."""
        await self._commands.run(CMD_ARM_DISARM, 1.0, arming=True)
        self.heard()

    async def take_off(self, flavor: Flavor, altitude_m: float) -> None:
        """The flight mode (ArduPilot GUIDED, PX4 OFFBOARD) and arm; ArduPilot then climbs to
        ``altitude_m`` [m] above home itself (refused: disarmed again, the refusal raised),
        PX4 on the setpoints the backend streams."""
        await self.set_mode(flavor.offboard_mode)
        await self.arm()
        if flavor.name == "ardupilot":
            try:
                await self._commands.run(CMD_NAV_TAKEOFF, *([0.0] * 6), altitude_m)
            except CommandRejectedError:
                await self.disarm_on_ground()
                raise

    async def land(self) -> None:
        """The autopilot's landing mode (ArduPilot LAND, PX4 AUTO.LAND) where the vehicle is."""
        await self.set_mode(self._flavor().land_mode)

    async def disarm_on_ground(self) -> None:
        """Armed but refused the take-off: disarm (best effort) so that it may be retried."""
        try:
            await self._commands.run(CMD_ARM_DISARM, 0.0)
            self.heard()
        except BackendError as exc:
            log.warning("vehicle %s: disarm after a refused take-off: %s",
                        self._state.system_id, exc)  # fmt: skip

    def landing_over(self, now_s: float) -> bool:
        """Whether a landing has ended at agent time ``now_s`` [s]: disarmed, heard since our
        last command, and in its ground mode with its pre-arm checks said there (asked for
        meanwhile, up to :data:`GROUND_MODE_WAIT_S`; then its pre-arm state says it is not in
        Hold yet)."""
        st = self._state
        if st.armed or st.heartbeats <= self.commanded_at:
            return False
        in_hold_unsaid = st.prearm_mode != st.custom_mode  # no SYS_STATUS in Hold yet
        if st.in_offboard_on_ground or in_hold_unsaid:
            return not self.ask_ground_mode(now_s, GROUND_MODE_WAIT_S)
        return True

    def ask_ground_mode(self, now_s: float, wait_s: float) -> bool:
        """Ask for the autopilot's ground mode (PX4: Hold) now and then, not awaited (a refusal
        leaves it where it is); False once asked for longer than ``wait_s`` [s], or when it has
        none."""
        flavor = self._flavor()
        if flavor.ground_mode is None:
            return False
        if math.isinf(self._ground_mode_since_s):
            self._ground_mode_since_s = now_s
        if now_s - self._ground_mode_asked_s >= GROUND_MODE_ASK_PERIOD_S:
            self._ground_mode_asked_s = now_s
            self._commands.send(CMD_DO_SET_MODE, *flavor.set_mode_params(flavor.ground_mode))
        return now_s - self._ground_mode_since_s < wait_s

    def stop_asking_ground_mode(self) -> None:
        """The backend's mode changed: a later ask for the ground mode waits ``wait_s`` anew."""
        self._ground_mode_since_s = math.inf

    async def force_disarm(self) -> None:
        """The e-stop: force-disarm now (motors off); best effort, logged if not confirmed."""
        try:
            await self._commands.run(CMD_ARM_DISARM, 0.0, FORCE_DISARM)
        except BackendError as exc:
            log.error("estop of vehicle %s not confirmed: %s", self._state.system_id, exc)


def disarmed_on_ground(state: LinkState) -> bool:
    """Disarmed and, as far as the autopilot says (EXTENDED_SYS_STATE), on the ground."""
    said = state.landed_state
    on_ground = said == MAV_LANDED_STATE_ON_GROUND if said is not None else True
    return not state.armed and on_ground


def refuse_recovery(
    state: LinkState, *, linked: bool, silent_s: float, heartbeat_timeout_s: float
) -> None:
    """Raise unless the autopilot of ``state``, ``linked`` and heard within its heartbeat
    timeout (silent for ``silent_s`` [s], at most ``heartbeat_timeout_s`` [s]), says it is
    disarmed on the ground: :class:`LinkLostError` without it, else :class:`BackendError`."""
    if not linked or not state.connected:
        raise LinkLostError("no link to the autopilot: it cannot be recovered")
    if not silent_s <= heartbeat_timeout_s:
        raise LinkLostError(f"no heartbeat from the autopilot for {silent_s:.1f} s")
    if state.armed:
        raise BackendError("its motors are still armed")
    if state.landed_state is not None and state.landed_state != MAV_LANDED_STATE_ON_GROUND:
        raise BackendError("the autopilot does not say it is on the ground")

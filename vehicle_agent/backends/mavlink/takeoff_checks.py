"""May the vehicle take off? What the MAVLink backend's ``takeoff`` checks before it sends a mode
change or an ARM, and the proof of life PX4 needs first.

- The autopilot's pre-arm checks: refused while SYS_STATUS says they fail, in the autopilot's
  words, asked for with MAV_CMD_RUN_PREARM_CHECKS if unsaid (and each tick while disarmed,
  :class:`PrearmAsker`, not awaited).
- The autopilot's position estimate: not ready while it is off the mocap pose sent to it (the
  snapshot's preflight says so, :func:`vehicle_agent.backends.mavlink.snapshot.off_the_mocap_m`).
- The vehicle's heading (ATTITUDE): refused when the vehicle has not said it.
- PX4's proof of life: a live setpoint stream before OFFBOARD and arming.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
from collections.abc import Callable

from vehicle_agent.backends.base import BackendError, Setpoint, Vec3
from vehicle_agent.backends.mavlink.commands import REASON_GRACE_S, CommandChannel
from vehicle_agent.backends.mavlink.connect import GCS_HEARTBEAT_PERIOD_S
from vehicle_agent.backends.mavlink.errors import (
    CommandRejectedError,
    EstimateOffMocapError,
    PrearmFailingError,
)
from vehicle_agent.backends.mavlink.snapshot import off_the_mocap_m
from vehicle_agent.backends.mavlink.state import LinkState
from vehicle_agent.backends.mavlink.stream import SetpointStream

CMD_NAV_TAKEOFF, CMD_RUN_PREARM_CHECKS = 22, 401
PREARM_ASK_PERIOD_S = 5.0
"""How often in [s] an autopilot whose pre-arm checks fail unexplained is asked why."""


async def refuse_while_prearm_fails(state: LinkState, commands: CommandChannel) -> None:
    """Raise :class:`PrearmFailingError` while SYS_STATUS says the pre-arm checks fail,
    having sent no mode change and no ARM (a ground station offers no arming then): the
    refusal the autopilot would give, in its words, asked for if it has not said them."""
    if state.preflight is None:
        return
    if state.prearm_text is None:
        with contextlib.suppress(BackendError):  # an autopilot without the command
            await commands.run(CMD_RUN_PREARM_CHECKS)
            await asyncio.sleep(REASON_GRACE_S)  # ArduPilot queues its texts after the ACK
    why = state.preflight  # None: they passed meanwhile
    if why is not None:
        raise PrearmFailingError(why)


def refuse_off_the_mocap(here_m_enu: Vec3, mocap_m_enu: Vec3 | None) -> None:
    """Raise :class:`EstimateOffMocapError`, nothing sent, when :func:`off_the_mocap_m`."""
    off_m = off_the_mocap_m(here_m_enu, mocap_m_enu)
    if off_m is not None:
        raise EstimateOffMocapError(off_m)


async def heading_ned_rad(state: LinkState) -> float:
    """The vehicle's heading in [rad] from north (ATTITUDE), held for the whole flight; a
    vehicle that has not said it within a second is refused the take-off (try again)."""
    for _ in range(20):
        if state.attitude_ned is not None:
            return state.attitude_ned[2]
        await asyncio.sleep(0.05)
    raise CommandRejectedError(
        CMD_NAV_TAKEOFF, 1, "no ATTITUDE from the vehicle yet: its heading is unknown"
    )


async def prove_life(
    stream: SetpointStream,
    hold: Setpoint,
    rate_hz: float,
    now_s: float,
    send_gcs_heartbeat: Callable[[], None],
) -> None:
    """PX4: OFFBOARD and arming need a live setpoint stream; stream a second and a bit of
    the current position (``hold``) at ``rate_hz`` on a running clock from agent time ``now_s``
    [s]."""
    for k in range(int(rate_hz) + 5):
        stream.send_proof_of_life(hold, now_s + k / rate_hz)
        if k % max(1, round(rate_hz * GCS_HEARTBEAT_PERIOD_S)) == 0:
            send_gcs_heartbeat()  # no tick meanwhile: stay a ground station for PX4
        await asyncio.sleep(1.0 / rate_hz)
    stream.last_sent_s = now_s  # the agent's clock did not run meanwhile


class PrearmAsker:
    """Asks the autopilot of ``state`` why its pre-arm checks fail, now and then."""

    def __init__(self, state: LinkState, commands: CommandChannel) -> None:
        self._state = state
        self._commands = commands
        self._asked_s = -math.inf
        """Agent time in [s] it was last asked."""

    def ask_why_not_ready(self, now_s: float) -> None:
        """SYS_STATUS says the pre-arm checks fail and the autopilot has not said why (it said
        it before we listened; ArduPilot repeats it only every 30 s): ask, as a ground
        station's "check" does, without waiting for the answer."""
        st = self._state
        unsaid = st.preflight is not None and st.prearm_text is None and not st.armed
        if unsaid and now_s - self._asked_s >= PREARM_ASK_PERIOD_S:
            self._asked_s = now_s
            self._commands.send(CMD_RUN_PREARM_CHECKS)

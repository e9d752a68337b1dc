"""PX4's home put where the vehicle stands, once the agent has moved its EKF's origin.

PX4 takes its home from the first position it has: PX4 SIH from its simulated GPS at boot. The
agent then gives EKF2 the show's origin for the mocap (:meth:`MocapForwarder.set_ekf_origin`),
and that home lies 3.9-4.0 m from where EKF2 now puts the vehicle (SIH starts at float32
coordinates, and every vehicle's frame is its own home on the show's origin). PX4's geofence
measures GF_MAX_HOR_DIST from home (3.5 m in ``shows/sitl-px4.yaml``), so its arming checks fail:
"Geofence: exceeding maximum distance to Home", and a vehicle sat held by its preflight for a
whole 12-job show (issue 31, PX4 1.16 SIH, 2026-11-30; PX4 re-homes at arming, which that check
forbids). MAV_CMD_DO_SET_HOME with param 1 = 1 puts the home where the vehicle is now, as PX4
would at arming: its fence is then the cylinder around the vehicle's pad the agent set it as
(:func:`~vehicle_agent.backends.mavlink.params.autopilot_fence`).
"""

from __future__ import annotations

import asyncio
import logging
import math
from collections.abc import Callable

from vehicle_agent.backends.mavlink.commands import CommandChannel
from vehicle_agent.backends.mavlink.errors import (
    MAV_RESULT_TEMPORARILY_REJECTED,
    CommandRejectedError,
    CommandTimeoutError,
    LinkLostError,
)

log = logging.getLogger(__name__)

CMD_DO_SET_HOME = 179
RETRY_S = 1.0
"""How long in [s] after an unanswered or temporarily rejected try the next one comes."""


class HomeSetter:
    """Sets the autopilot's home where the vehicle stands, once, when it is ready for it."""

    def __init__(self, commands: CommandChannel) -> None:
        self._commands = commands
        self.done = False
        """Set (or refused for good: COM_HOME_EN 0, PX4 keeps its own)."""
        self._task: asyncio.Task[None] | None = None
        self._tried_s = -math.inf

    def step(self, now_s: float, ready: Callable[[], bool]) -> None:
        """``ready()``: the EKF is on our origin, the vehicle disarmed on the ground and its
        estimate on the mocap (asked only while a try is due). Starts a try (not awaited) at
        agent time ``now_s`` [s]."""
        busy = self._task is not None and not self._task.done()
        if self.done or busy or now_s - self._tried_s < RETRY_S or not ready():
            return
        self._tried_s = now_s
        self._task = asyncio.get_running_loop().create_task(self._set_home_here())

    async def _set_home_here(self) -> None:
        try:
            await self._commands.run(CMD_DO_SET_HOME, 1.0)
        except (CommandTimeoutError, LinkLostError):
            return
        except CommandRejectedError as exc:
            if exc.result == MAV_RESULT_TEMPORARILY_REJECTED:  # no position yet
                return
            log.warning("home not set where the vehicle stands: %s", exc)
        self.done = True

    def cancel(self) -> None:
        if self._task is not None:
            self._task.cancel()

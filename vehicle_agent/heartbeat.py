"""What an agent says of itself on the bus, its status and telemetry, and the heartbeat that
keeps it from going silent.

The status goes out when it changes (each tick), after a command, and as a heartbeat
(:func:`status_due_s`): the status at least every ``status_period_s``, and something of its
own (status or telemetry) at least every 1.1 ``lost_after_s / 3`` (the orchestrator takes a
silent vehicle as lost, token or not). The heartbeat is also the agent's stall detector: when
its task wakes up late, nothing of the agent ran meanwhile (frozen, starved), whatever the
control loop was doing; the lateness is handed to the job lease before the next tick
(``vehicle_agent/job_guard.py``).
"""

from __future__ import annotations

import asyncio
import math
import time
from collections.abc import Callable

from bus.messages import Telemetry, VehicleStatus
from bus.pubsub import MessagePublisher, publish
from bus.session import Session

HEARTBEAT_SLACK_S = 0.005
"""A heartbeat status due within this is sent now rather than after a sleep that short, [s]."""
SILENCE_SHARE = 1.1 / 3.0
"""The longest an agent stays silent, as a share of ``lost_after_s`` (:func:`status_due_s`)."""


class StatusHeartbeat:
    """Publishes the statuses ``compose`` makes on ``status_key`` and the telemetry on
    ``telemetry_key`` of one agent's ``session``; its :meth:`run` is the heartbeat."""

    def __init__(
        self,
        session: Session,
        status_key: str,
        telemetry_key: str,
        compose: Callable[[], VehicleStatus],
        *,
        status_period_s: float,
        lost_after_s: float,
    ) -> None:
        self._session = session
        self._status_key = status_key
        self._telemetry = MessagePublisher(session, telemetry_key)
        self._compose = compose
        self._status_period_s = status_period_s
        self._lost_after_s = lost_after_s
        self._status_sent: VehicleStatus | None = None
        self._status_at_s = -math.inf
        """Wall (monotonic) time in [s] of the latest status published."""
        self._spoke_at_s = -math.inf
        """Wall (monotonic) time in [s] of the latest status or telemetry published."""
        self._stalled_s = 0.0
        """The longest the heartbeat woke up late in [s] since :meth:`take_stalled`."""

    def publish_status(self, *, only_if_changed: bool = False) -> None:
        """Publish the status as it is now (``only_if_changed``: unless it is the last one)."""
        status = self._compose()
        if only_if_changed and status == self._status_sent:
            return
        self._status_sent = status
        publish(self._session, self._status_key, status)
        self._status_at_s = self._spoke_at_s = time.monotonic()

    def publish_telemetry(self, telemetry: Telemetry) -> None:
        """Publish one telemetry message (it counts as the agent speaking)."""
        self._telemetry.put(telemetry)
        self._spoke_at_s = time.monotonic()

    def take_stalled(self) -> float:
        """The longest stall in [s] seen since the last call (0 when none)."""
        stalled_s, self._stalled_s = self._stalled_s, 0.0
        return stalled_s

    async def run(self) -> None:
        """The heartbeat and stall detector (see the module docstring), until cancelled."""
        while True:
            due_s = status_due_s(
                self._status_at_s, self._spoke_at_s, self._status_period_s, self._lost_after_s
            )
            if time.monotonic() >= due_s - HEARTBEAT_SLACK_S:
                self.publish_status()
                continue
            sleep_s = due_s - time.monotonic()
            slept_from_s = time.monotonic()
            await asyncio.sleep(sleep_s)
            late_s = time.monotonic() - slept_from_s - sleep_s
            self._stalled_s = max(self._stalled_s, late_s)


def status_due_s(
    status_at_s: float, spoke_at_s: float, status_period_s: float, lost_after_s: float
) -> float:
    """When the next heartbeat status is due, [s] (the clock of the arguments): a status at
    least every ``status_period_s``, and something (status or telemetry) at least every
    ``lost_after_s / 3`` and a tenth. A vehicle at rest sends its telemetry at 1 Hz: its status
    goes out half-way between (1 Hz too), so the orchestrator hears it every 0.5 s with two
    messages a second, where a status every ``lost_after_s / 4`` beside that telemetry made 3.7
    (the orchestrator and the router spend per message: 250 vehicles sent 900 a second). The
    tenth lets the telemetry, due half a second after the status, go first: without it the two
    were due at the same instant and the status often won (1.8 statuses a second measured)."""
    return min(status_at_s + status_period_s, spoke_at_s + SILENCE_SHARE * lost_after_s)

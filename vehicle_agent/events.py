"""Events about one vehicle (autopilot STATUSTEXT, a refused take-off, a job given up), queued
for the agent service to publish on ``vehicles/<id>/events``."""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable
from typing import Literal

from bus.messages import Event

Level = Literal["info", "warning", "alert"]
MAV_SEVERITY_DEBUG = 7


class EventOutbox:
    """Events about one vehicle waiting to be published; filled from the backend's callbacks
    (on the event loop) and by the service. A text repeated within ``repeat_after_s`` is dropped
    (autopilots repeat their pre-arm complaints)."""

    def __init__(
        self,
        vehicle_id: str,
        *,
        clock: Callable[[], float] = time.time,
        repeat_after_s: float = 10.0,
        max_events: int = 100,
    ) -> None:
        self.vehicle_id = vehicle_id
        self._clock = clock
        self._repeat_after_s = repeat_after_s
        self._events: deque[Event] = deque(maxlen=max_events)
        self._last_said: dict[str, float] = {}
        self._max_remembered = 4 * max_events

    def push(self, level: Level, kind: str, message: str, *, job_id: str | None = None) -> None:
        """Queue one event (Unix time now)."""
        now = self._clock()
        said_at = self._last_said.get(message)
        if said_at is not None and now - said_at < self._repeat_after_s:
            return
        if len(self._last_said) > self._max_remembered:
            self._last_said.clear()
        self._last_said[message] = now
        event = Event(
            time_s=now,
            level=level,
            kind=kind,
            message=message,
            vehicle_id=self.vehicle_id,
            job_id=job_id,
        )
        self._events.append(event)

    def autopilot_text(self, severity: int, text: str) -> None:
        """A STATUSTEXT of the vehicle's autopilot (MAV_SEVERITY 0..7; debug is dropped)."""
        if severity >= MAV_SEVERITY_DEBUG:
            return
        level: Level = "alert" if severity <= 2 else "warning" if severity <= 4 else "info"
        self.push(level, "autopilot", f"{self.vehicle_id} autopilot: {text.strip()}")

    def drain(self) -> list[Event]:
        """The queued events, oldest first; the outbox is then empty."""
        events = list(self._events)
        self._events.clear()
        return events

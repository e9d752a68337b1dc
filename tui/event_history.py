"""The console's event log: the show's events and the console's own notes, numbered (pure).

Each event gets the next sequence number, so a view adds only those it has not shown yet
(:meth:`EventHistory.after`); the newest ``max_events`` are kept. A late joiner's snapshot brings
the show's recent events: only those newer than any of the show's already logged are added
(the console's own notes never hide them).
"""

from __future__ import annotations

from collections import deque
from typing import Literal

from bus.messages import CommandReply, Event, OperatorCommand


class EventHistory:
    """Events the console keeps, oldest first, each with its sequence number."""

    def __init__(self, max_events: int = 500) -> None:
        self._events: deque[tuple[int, Event]] = deque(maxlen=max_events)
        self._seq = 0
        self._show_event_s = float("-inf")
        """Time of the newest event of the show (not the console's own notes) in the log."""

    @property
    def seq(self) -> int:
        """Sequence number of the newest event."""
        return self._seq

    def after(self, seq: int) -> list[tuple[int, Event]]:
        """Events with a sequence number above ``seq`` (0 for all kept), oldest first."""
        return [(s, e) for s, e in self._events if s > seq]

    def add(self, event: Event) -> None:
        self._seq += 1
        self._events.append((self._seq, event))

    def show_event(self, event: Event) -> None:
        """An event of the show, live from the bus."""
        self._show_event_s = max(self._show_event_s, event.time_s)
        self.add(event)

    def history(self, events: list[Event]) -> None:
        """The show's recent events from a snapshot: those newer than any already logged."""
        for event in events:
            if event.time_s > self._show_event_s:
                self._show_event_s = event.time_s
                self.add(event)

    def note(
        self,
        now_s: float,
        level: Literal["info", "warning", "alert"],
        kind: str,
        message: str,
        *,
        vehicle_id: str | None = None,
    ) -> None:
        """An event of the console itself (operator actions, answers, presence)."""
        self.add(
            Event(time_s=now_s, level=level, kind=kind, message=message, vehicle_id=vehicle_id)
        )

    def command_refused(self, command: OperatorCommand, reply: CommandReply, now_s: float) -> None:
        """A refused or unanswered operator command and the orchestrator's answer."""
        target = command.job_id or command.vehicle_id or ""
        answer = reply.message or "refused"
        if reply.error is not None:
            answer = f"{answer}: {reply.error.message}" if reply.message else reply.error.message
        self.note(
            now_s,
            "warning",
            "command",
            f"{command.command} {target}".rstrip() + f" -> {answer}",
            vehicle_id=command.vehicle_id,
        )

"""The show's event log, newest at the bottom; alerts in red, warnings in yellow."""

from __future__ import annotations

from rich.text import Text
from textual.widgets import RichLog

from bus.messages import Event
from tui import format as fmt
from tui.safe_text import clean

LEVEL_STYLES = {"info": "", "warning": "yellow", "alert": "bold white on red"}


def event_line(event: Event) -> Text:
    """``12:03:04 vehicle_lost uav2: lost after 1.5 s`` (bus strings as plain, cleaned text)."""
    text = Text(no_wrap=True, overflow="ellipsis")
    text.append(fmt.clock(event.time_s), style="dim")
    text.append(f" {clean(event.kind, 32)} ", style="bold")
    subject = event.vehicle_id or event.job_id
    if subject:
        text.append(f"{clean(subject, 40)}: ")
    text.append(clean(event.message))
    text.stylize(LEVEL_STYLES.get(event.level, ""), 9)
    return text


class EventLog(RichLog, can_focus=False):
    """Appends only what is new; optionally only one vehicle's events. Not a Tab stop: no key
    acts on it (Tab moves between the fleet and the queue; ``skyquill log`` reads the whole
    log)."""

    def __init__(self, *, vehicle_id: str | None = None, **kwargs: object) -> None:
        super().__init__(max_lines=500, wrap=False, **kwargs)  # type: ignore[arg-type]
        self.vehicle_id = vehicle_id
        """Show only events about this vehicle (detail view)."""
        self.last_seq = 0
        """Sequence number of the newest event written."""

    def add_events(self, events: list[tuple[int, Event]]) -> None:
        for seq, event in events:
            if seq <= self.last_seq:
                continue
            self.last_seq = seq
            if self.vehicle_id is None or event.vehicle_id == self.vehicle_id:
                self.write(event_line(event))

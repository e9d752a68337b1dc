"""The main screen's views brought in line with the pure :class:`~tui.model.ConsoleModel`.

The model counts its changes per part (``fleet_version``, ``queue_version``, ``tracks_version``,
the event log's ``seq``, ``version`` for all of them); a :class:`Redrawer` remembers what each
view last drew and redraws only the parts that changed. The app decides when to redraw
(:class:`~tui.throttle.RedrawThrottle`); the fleet table's numbers follow at most
:data:`TABLE_HZ` times per second.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from bus.messages import CommandReply, OperatorCommand
from tui.format import job_totals_text
from tui.model import ConsoleModel
from tui.throttle import RedrawThrottle
from tui.widgets.alert_bar import AlertBar
from tui.widgets.board_grid import BoardGrid
from tui.widgets.board_strip import BoardStrip
from tui.widgets.event_log import EventLog
from tui.widgets.fleet_table import FleetTable
from tui.widgets.header_bar import HeaderBar
from tui.widgets.preview_pane import PreviewPane
from tui.widgets.queue_table import QueueTable

TABLE_HZ = 5.0
"""Highest update rate of the fleet table's numbers, in [Hz]."""


class Redrawer:
    """Draws the model into the main screen's views; ``bell`` rings for each new alert."""

    def __init__(
        self,
        model: ConsoleModel,
        *,
        redraw_hz: float,
        slack_s: float,
        bell: Callable[[], None],
        header: HeaderBar,
        alerts: AlertBar,
        fleet: FleetTable,
        strip: BoardStrip,
        boards: BoardGrid,
        queue: QueueTable,
        preview: PreviewPane,
        event_log: EventLog,
    ) -> None:
        self.model = model
        self.table_throttle = RedrawThrottle(min(redraw_hz, TABLE_HZ), slack_s=slack_s)
        """Numbers are unreadable above a few changes per second; paths are drawn faster."""
        self._bell = bell
        self._header = header
        self._alerts = alerts
        self._fleet = fleet
        self._strip = strip
        self._boards = boards
        self._queue = queue
        self._preview = preview
        self._event_log = event_log
        self._drawn: dict[str, int] = {}
        self._drawn_boards: tuple[int, int, int] | None = None
        self._alerted: set[str] = set()

    @property
    def stale(self) -> bool:
        """The model changed since the views last drew all of it."""
        return self.model.version != self._drawn.get("all")

    def redraw(self, now_s: float) -> None:
        """Bring every view in line with the model (only the parts that changed)."""
        self._redraw_status()
        table_done = self._redraw_fleet(now_s)
        self._redraw_queue()
        self._redraw_boards(now_s)
        if self.model.events.seq != self._event_log.last_seq:
            self._event_log.add_events(self.model.events.after(self._event_log.last_seq))
        if table_done:  # else the next tick comes back for the table
            self._drawn["all"] = self.model.version

    def show_strip(self, hidden_boards: bool, now_s: float) -> None:
        """The compact board strip shows while some boards are out of sight."""
        self._strip.display = hidden_boards
        if self._strip.display:
            self._strip.sync(now_s)

    def forget_boards(self) -> None:
        """Redraw the boards at the next redraw even if nothing changed (their size did)."""
        self._drawn_boards = None

    def _redraw_status(self) -> None:
        m = self.model
        self._header.orchestrator = m.orchestrator
        self._header.queue_paused = m.queue_paused
        self._header.can_fly = m.can_fly_count()
        self._header.faults = len(m.fault_ids())
        self._header.awaiting = m.awaiting_count()
        counts = m.state_counts()
        text = f"{sum(counts.values())} vehicles, {counts.get('writing', 0)} writing"
        text += f", {counts['lost']} lost" if counts.get("lost") else ""
        self._header.counts = text + job_totals_text(m.job_counts)
        if m.last_reply is not None:
            command, reply = m.last_reply
            self._header.last_reply = answer_text(command, reply)
            self._header.last_reply_ok = reply.ok
        alerts = m.alerts()
        self._alerts.alerts = tuple(alert.message for alert in alerts)
        keys = {alert.key for alert in alerts}
        if keys - self._alerted:
            self._bell()  # a new alert: the operator may be looking elsewhere
        self._alerted = keys

    def _redraw_fleet(self, now_s: float) -> bool:
        """Update the fleet table if it is due; False when it changed but had to wait."""
        dirty = self._drawn.get("table") != self.model.fleet_version
        if not self.table_throttle.due(time.monotonic(), dirty):
            return not dirty
        self._drawn["table"] = self.model.fleet_version
        self._fleet.show_rows(self.model.vehicle_rows(now_s))
        self.show_strip(not self._boards.all_visible, now_s)  # at the table's (lower) rate
        return True

    def _redraw_queue(self) -> None:
        if self._drawn.get("queue") != self.model.queue_version:
            self._drawn["queue"] = self.model.queue_version
            self._queue.show_rows(self.model.queue_rows())
            self._preview.job = self.model.job(self._queue.selected_job)

    def _redraw_boards(self, now_s: float) -> None:
        m = self.model
        key = (m.tracks_version, m.fleet_version, round(self._boards.scroll_y))
        if self._drawn_boards != key:  # new samples, new states, or other boards scrolled in
            self._drawn_boards = key
            self._boards.sync(now_s)


def answer_text(command: OperatorCommand, reply: CommandReply) -> str:
    """A command and the orchestrator's answer to it, in one line."""
    if reply.error is not None:
        answer = f"{reply.message + ': ' if reply.message else ''}{reply.error.message}"
    else:
        answer = reply.message or ("ok" if reply.ok else "refused")
    return f"{command.command}: {answer}"

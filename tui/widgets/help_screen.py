"""Every key of the console and what it acts on (``?`` or F1)."""

from __future__ import annotations

from typing import ClassVar

from rich.table import Table
from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import VerticalScroll
from textual.screen import ModalScreen
from textual.widgets import Static

HELP: tuple[tuple[str, str, str], ...] = (
    ("Tab", "move between the fleet and the queue", "focus"),
    ("↑ ↓ PgUp PgDn", "select a vehicle or a job", "focused table"),
    ("a", "approve the submission", "selected job (queue focused)"),
    ("r", "reject it, with an optional reason (confirmed)", "selected job (queue focused)"),
    ("c", "cancel the job, with an optional reason (confirmed)", "selected job (queue focused)"),
    ("+ / -", "raise / lower the waiting job's priority", "selected job (queue focused)"),
    ("v", "full-screen preview of the drawing", "selected job (queue focused)"),
    ("space", "mark / unmark a waiting job for R", "selected job (queue focused)"),
    ("M", "mark every waiting job of that client (again: unmark)", "selected job's client"),
    ("R", "reject the marked jobs (queued ones: cancel), one question", "marked (queue focused)"),
    ("l", "land; it stays held on the ground (confirmed)", "selected vehicle (fleet focused)"),
    ("u", "release a held vehicle: it may fly again (confirmed)", "selected vehicle"),
    ("f", "reset a vehicle in fault after an E-STOP (confirmed)", "selected vehicle"),
    ("F", "reset every vehicle in fault (confirmed)", "whole fleet"),
    ("U", "release every held vehicle (confirmed)", "whole fleet"),
    ("s", "fresh sheet: a board waiting for one is written on again", "selected vehicle's board"),
    ("b", "battery swapped: a vehicle in battery swap flies again (confirmed)", "selected vehicle"),
    ("Enter / d", "details of the vehicle", "selected vehicle (fleet focused)"),
    ("m", "venue plan: boards, homes, geofences and vehicles to scale", "whole venue"),
    ("p", "pause / resume the queue (held vehicles stay held)", "queue"),
    ("P", "pause a vehicle: no new job / resume it (confirmed)", "selected vehicle"),
    ("L", "land every vehicle, pause the queue (confirmed)", "whole fleet"),
    ("e", "EMERGENCY STOP: motors off (confirmed)", "whole fleet; one vehicle in details"),
    ("x", "acknowledge the alerts shown", "alert line"),
    ("? / F1", "this help", ""),
    ("Esc / q", "back (details, venue plan, preview, help)", "this screen"),
    ("q / Ctrl+C", "quit the console (asks while vehicles fly); the show keeps running", ""),
)
"""Keys, what they do and what they act on; the footer shows those that act now."""


BOARD_MARKS = (
    "boards line (small terminals): b1工 writing 工 · b2^ in the air · b4· idle · ! fault · "
    "✖ lost · B battery swap (b) · H held · P paused · ✎ waits for a fresh sheet (s)"
)
"""The legend of the compact board strip (``tui/widgets/board_strip.py``)."""


def help_table() -> Table:
    table = Table(box=None, padding=(0, 1), expand=True)
    table.add_column("key", style="bold cyan", no_wrap=True)
    table.add_column("does")
    table.add_column("acts on", style="dim")
    for keys, does, target in HELP:
        table.add_row(Text(keys), Text(does), Text(target))
    return table


class HelpScreen(ModalScreen[None]):
    """The key table; any of Escape, q, ? or F1 closes it."""

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("escape,q,question_mark,f1", "app.pop_screen", "back"),
    ]

    def compose(self) -> ComposeResult:
        with VerticalScroll(id="help-dialog"):
            yield Static(help_table(), id="help-table")
            yield Static(Text(BOARD_MARKS, style="dim"), id="help-legend")

    def on_mount(self) -> None:
        self.query_one("#help-dialog").border_title = "keys (Esc: back)"

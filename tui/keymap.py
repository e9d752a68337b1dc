"""The console's keys: which action each one runs, and when it acts.

The actions themselves (``action_*``) are the app's (:mod:`tui.app`); their text for the operator
is the help screen's (:data:`tui.widgets.help_screen.HELP`).
"""

from __future__ import annotations

from typing import Literal

from textual.binding import Binding, BindingType
from textual.screen import Screen

from tui.widgets.confirm_screen import ConfirmScreen
from tui.widgets.help_screen import HelpScreen
from tui.widgets.preview_screen import PreviewScreen
from tui.widgets.vehicle_detail_screen import VehicleDetailScreen
from tui.widgets.venue_screen import VenueScreen

KEYS: list[BindingType] = [  # E-STOP and help first: the footer keeps them
    Binding("e", "estop", "E-STOP"),
    Binding("question_mark,f1", "help", "help"),
    Binding("a", "approve", "approve"),
    Binding("r", "reject", "reject"),
    Binding("c", "cancel_job", "cancel"),
    Binding("plus", "priority('raise')", "prio+"),
    Binding("minus", "priority('lower')", "prio-"),
    Binding("v", "preview", "view"),
    Binding("space", "mark", "mark", show=False),
    Binding("M", "mark(True)", "mark client", show=False),
    Binding("R", "reject_marked", "reject marked", show=False),
    Binding("l", "vehicle('land')", "land"),
    Binding("u", "vehicle('release')", "release"),
    Binding("f", "vehicle('clear_fault')", "reset fault"),
    Binding("F", "clear_all", "reset all", show=False),
    Binding("U", "release_all", "release all", show=False),
    Binding("s", "fresh_sheet", "fresh sheet", show=False),
    Binding("b", "vehicle('battery_swapped')", "battery swapped", show=False),
    Binding("d", "detail", "detail", show=False),
    Binding("m", "venue", "venue plan", show=False),
    Binding("p", "toggle_pause", "pause"),
    Binding("P", "vehicle('pause')", "pause vehicle", show=False),
    Binding("L", "land_all", "land all"),
    Binding("x", "acknowledge", "ack", show=False),
    Binding("q", "quit", "quit", show=False),
    Binding("ctrl+c", "quit", "quit", show=False, priority=True),  # as q: a terminal's habit
]
"""Every key of the main screen (the app's ``BINDINGS``)."""
JOB_ACTIONS = frozenset(
    {"approve", "reject", "cancel_job", "priority", "preview", "mark", "reject_marked"}
)
"""Act on the job selected in the queue: only while the queue has the focus."""
VEHICLE_ACTIONS = frozenset({"vehicle", "detail", "fresh_sheet"})
"""Act on the vehicle selected in the fleet table: only while the fleet has the focus."""
Focus = Literal["queue", "fleet"] | None
"""The table with the focus, if any."""


def acts_now(action: str, screen: Screen[object], depth: int, focus: Focus) -> bool:
    """Only the keys that act now: job keys with the queue focused, vehicle keys with the
    fleet focused (so a command never acts on a selection out of sight), none behind a
    question; the detail view has its own keys. ``screen``: the one on top of the ``depth``
    screens."""
    if action == "pop_screen":  # "back" of the screens above the main one
        return depth > 1
    if isinstance(screen, ConfirmScreen | HelpScreen | PreviewScreen):
        return action == "quit" and not isinstance(screen, ConfirmScreen)
    if isinstance(screen, VehicleDetailScreen | VenueScreen):
        return action in ("quit", "land_all", "estop", "help")
    if action in JOB_ACTIONS:
        return focus == "queue"
    if action in VEHICLE_ACTIONS:
        return focus == "fleet"
    return True

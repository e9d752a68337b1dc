"""Every board on one line, for terminals too small to draw them all (e.g. 80x24)."""

from __future__ import annotations

import time
from collections.abc import Callable

from rich.text import Text
from textual.widget import Widget

from tui import format as fmt
from tui.model import ConsoleModel
from tui.safe_text import clean
from tui.settings import ConsoleSettings

SEPARATOR = " │ "
STRIP_HZ = 2.0
"""Highest update rate of the strip, in [Hz]: a summary, the boards themselves are drawn faster."""


def board_entry(model: ConsoleModel, board_id: str, now_s: float) -> Text:
    """``b1 uav1 «工» 55%``, ``b3 uav3 lost``: one board, short (bus strings cleaned)."""
    entry = Text(clean(board_id, 12), style="bold")
    for vid in model.vehicles_on_board(board_id):
        row = model.vehicle_row(vid, now_s)
        if row is None:
            continue
        entry.append(f" {clean(vid, 12)} ")
        if row.job_label:
            entry.append(f"«{clean(row.job_label, 6)}» {100 * row.progress:.0f}%")
        else:
            entry.append_text(fmt.vehicle_state_text(row.state, row.held, row.paused))
    if board_id in model.dirty_boards:
        entry.append(" new sheet?", style="bold black on yellow")
    return entry


SYMBOLS = {
    "fault": ("!", "bold red"),
    "lost": ("✖", "bold white on red"),
    "idle": ("·", "green"),
    "battery_swap": ("B", "bold black on yellow"),
}
"""Compact marks of a board's vehicle states (others: ``^``, in the air)."""


def compact_entry(model: ConsoleModel, board_id: str, now_s: float) -> Text:
    """``b1工`` writing, ``b2^`` flying, ``b3✖`` lost, ``b4·`` idle, ``B`` battery swap, ``H``
    held, ``P`` paused, ``✎`` new sheet (the legend: ``help_screen.BOARD_MARKS``)."""
    entry = Text(clean(board_id, 8), style="bold")
    for vid in model.vehicles_on_board(board_id):
        row = model.vehicle_row(vid, now_s)
        if row is None:
            continue
        if row.job_label:
            entry.append(clean(row.job_label, 2), style="bold #00d7ff")
        else:
            mark, style = SYMBOLS.get(row.state, ("^", "cyan"))
            entry.append(mark, style=style)
        if row.held:
            entry.append("H", style="bold black on yellow")
        elif row.paused:
            entry.append("P", style="bold black on cyan")
    if board_id in model.dirty_boards:
        entry.append("✎", style="bold black on yellow")
    return entry


def strip_text(model: ConsoleModel, settings: ConsoleSettings, now_s: float, width: int) -> Text:
    """Every board in full if they fit, else every board compact if they fit, else as many
    compact ones as fit and ``+N``; nothing is cut mid-word."""
    full, complete = _strip(model, settings, now_s, width, board_entry, SEPARATOR)
    if complete:
        return full
    return _strip(model, settings, now_s, width, compact_entry, " ")[0]


def _strip(
    model: ConsoleModel,
    settings: ConsoleSettings,
    now_s: float,
    width: int,
    entry_of: Callable[[ConsoleModel, str, float], Text],
    separator: str,
) -> tuple[Text, bool]:
    """As many whole boards as fit in ``width`` cells, then ``+N``; boards that need the
    operator (a fresh sheet) come first; only the boards shown are built. True: all shown."""
    boards = sorted(settings.boards, key=lambda b: b.board_id not in model.dirty_boards)
    text = Text(no_wrap=True)
    for i, board in enumerate(boards):
        entry = entry_of(model, board.board_id, now_s)
        more = len(boards) - i - 1
        tail = len(f"{separator}+{more}") if more else 0
        if text.cell_len + (len(separator) if i else 0) + entry.cell_len + tail > width:
            text.append(f"{separator if i else ''}+{len(boards) - i}", style="dim")
            return text, False
        if i:
            text.append(separator, style="dim")
        text.append_text(entry)
    return text, True


class BoardStrip(Widget):
    """Shown (by the app) only while the board grid cannot show every board."""

    def __init__(self, model: ConsoleModel, settings: ConsoleSettings, **kwargs: object) -> None:
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.model = model
        self.settings = settings
        self._shown = ""
        self._text = Text()
        self._now_s = 0.0
        self._synced_s = -1e9
        self._pending = False

    def sync(self, now_s: float) -> None:
        """Redraw if what the strip says changed (at most ``STRIP_HZ`` times a second)."""
        self._now_s = now_s
        wait_s = self._synced_s + 1.0 / STRIP_HZ - time.monotonic()
        if self._shown and wait_s > 0:
            if not self._pending:  # come back once, so the last change is never left out
                self._pending = True
                self.set_timer(wait_s, self._deferred)
            return
        self._synced_s = time.monotonic()
        self._update()

    def _deferred(self) -> None:
        self._pending = False
        self._synced_s = time.monotonic()
        self._update()

    def on_resize(self) -> None:
        self._update()

    def _update(self) -> None:
        width = self.content_size.width
        text = strip_text(self.model, self.settings, self._now_s, width) if width else Text()
        if text.plain != self._shown:
            self._shown, self._text = text.plain, text
            self.refresh()

    def render(self) -> Text:
        return self._text

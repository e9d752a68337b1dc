"""All boards in a scrolling grid whose column count follows the terminal's width."""

from __future__ import annotations

from textual.containers import VerticalScroll
from textual.events import Resize
from textual.message import Message

from tui.widgets.board_view import BoardView

MIN_BOARD_COLS = 30
"""Narrowest board view, in terminal cells (a legible character needs ~24 x 8 cells)."""
MIN_BOARD_ROWS = 9


def grid_shape(count: int, width: int, height: int) -> tuple[int, int]:
    """Columns of the grid and rows per board for ``count`` boards in ``width`` x ``height``.

    Boards are at least ``MIN_BOARD_COLS`` wide; as many rows of boards as fit at least
    ``MIN_BOARD_ROWS`` high share the visible height exactly (the rest scroll), and a single row
    of boards takes the whole height even when it is lower than the minimum.
    """
    columns = max(1, min(max(count, 1), width // MIN_BOARD_COLS))
    grid_rows = max(1, -(-count // columns))
    visible_rows = max(1, min(grid_rows, height // MIN_BOARD_ROWS))
    return columns, max(1, height // visible_rows)


class BoardGrid(VerticalScroll, can_focus=False):
    """Holds one :class:`BoardView` per board."""

    all_visible = True
    """Every board is (at least partly) on screen without scrolling."""

    class Relaid(Message):
        """Whether every board fits on screen changed."""

        def __init__(self, all_visible: bool) -> None:
            super().__init__()
            self.all_visible = all_visible

    def on_resize(self, event: Resize) -> None:
        self._relayout(event.size.width, event.size.height)

    def _relayout(self, width: int, height: int) -> None:
        count = len(self.query(BoardView))
        columns, rows = grid_shape(count, width, height)
        self.styles.grid_size_columns = columns
        self.styles.grid_rows = str(rows)
        all_visible = count <= columns * max(1, height // rows)
        if all_visible != self.all_visible:
            self.all_visible = all_visible
            self.post_message(self.Relaid(all_visible))

    def sync(self, now_s: float) -> None:
        """Let each board draw what is new."""
        for board in self.query(BoardView):
            board.sync(now_s)

"""The queue's cursor after a moderation, and its priority column (``tui/widgets/queue_table``)."""

from __future__ import annotations

from test_tui_model import job

from tui.rows import QueueRow
from tui.widgets.queue_table import cursor_after, row_cells


def _rows(awaiting: list[str], queued: list[str]) -> list[QueueRow]:
    return [QueueRow("awaiting", job(j, "awaiting_approval")) for j in awaiting] + [
        QueueRow("queued", job(j, "queued")) for j in queued
    ]


def test_approving_moves_the_cursor_to_the_next_submission_not_after_the_job() -> None:
    before = _rows(["j1", "j2", "j3"], [])
    assert cursor_after("j1", before, _rows(["j2", "j3"], ["j1"])) == "j2"
    assert cursor_after("j3", before, _rows(["j1", "j2"], ["j3"])) == "j2"  # the last one left
    assert cursor_after("j2", before, _rows([], ["j1", "j2", "j3"])) == "j2"  # none left: follow


def test_the_cursor_stays_on_its_job_otherwise() -> None:
    before = _rows(["j1"], ["j2"])
    assert cursor_after("j2", before, _rows(["j1"], ["j2", "j4"])) == "j2"
    assert cursor_after("j1", before, _rows(["j4", "j1"], ["j2"])) == "j1"
    assert cursor_after(None, before, _rows(["j1"], [])) is None


def test_the_priority_shows_only_when_moved() -> None:
    cells = row_cells(QueueRow("queued", job("j1", "queued", priority=2)))
    assert [c.plain for c in cells][2] == "+2"
    assert row_cells(QueueRow("queued", job("j1", "queued")))[2].plain == ""

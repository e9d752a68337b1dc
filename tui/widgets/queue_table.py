"""The queue: awaiting approval, queued with ETA, active, done with metrics, failed with reason.

The operator marks waiting jobs here (``space`` one, ``M`` every waiting job of a client) for one
bulk reject; a mark lasts while its job waits.
"""

from __future__ import annotations

from typing import ClassVar

from rich.text import Text
from textual.binding import Binding, BindingType
from textual.message import Message
from textual.widgets import DataTable

from bus.messages import JobState
from tui import format as fmt
from tui.rows import QueueRow
from tui.safe_text import clean

COLUMNS = (
    ("section", "State"),
    ("char", "Char"),
    ("prio", "Prio"),
    ("job", "Job"),
    ("detail", "Detail"),
)
"""Job ids before the details, which are the widest: a narrow queue still shows every id. The
priority (``+``/``-`` move it) is blank at 0, the default, so the ones moved stand out."""

Cells = tuple[Text, ...]
MARKABLE = frozenset({"awaiting", "queued"})
"""Sections whose jobs may be marked: those a bulk reject or cancel takes."""
MARK = Text("● ", style="bold magenta")
"""Before the state of a marked job."""


def row_cells(row: QueueRow, marked: bool = False) -> Cells:
    """The cells of one job: Text only, as DataTable reads a ``str`` cell as markup."""
    return (
        MARK + fmt.section_text(row) if marked else fmt.section_text(row),
        _char(row.job),
        Text(f"{row.job.priority:+d}" if row.job.priority else "", style="bold"),
        Text(fmt.short_id(row.job.job_id)),
        Text(fmt.job_detail(row)),
    )


def _char(job: JobState) -> Text:
    """The character; a phrase's with its place in it (``新 ⁞1/4``), so its jobs read as one."""
    text = Text(fmt.short_id(job.label, 12), style="bold")
    if job.phrase is not None:
        text.append(f" ⁞{job.phrase.index + 1}/{job.phrase.size}", style="cyan")
    return text


class QueueTable(DataTable[Text]):
    """Jobs by section; the cursor selects the job that approve/reject/cancel act on."""

    BINDINGS: ClassVar[list[BindingType]] = [  # as in the fleet: the first and the last job
        Binding("home", "scroll_top", "first", show=False),
        Binding("end", "scroll_bottom", "last", show=False),
    ]

    class JobHighlighted(Message):
        """The cursor moved to another job (or to none)."""

        def __init__(self, job_id: str | None) -> None:
            super().__init__()
            self.job_id = job_id

    def __init__(self, **kwargs: object) -> None:
        super().__init__(cursor_type="row", **kwargs)  # type: ignore[arg-type]
        self._keys: list[str] = []
        self._shown: dict[str, Cells] = {}
        self._rows: dict[str, QueueRow] = {}
        self._marked: set[str] = set()

    def on_mount(self) -> None:
        for key, label in COLUMNS:
            self.add_column(label, key=key)

    @property
    def selected_job(self) -> str | None:
        """Job under the cursor."""
        if not self.row_count:
            return None
        row_key, _ = self.coordinate_to_cell_key(self.cursor_coordinate)
        return row_key.value

    def marked_jobs(self) -> list[JobState]:
        """The marked jobs, in the table's order."""
        return [self._rows[key].job for key in self._keys if key in self._marked]

    def toggle_mark(self) -> str | None:
        """Mark the job under the cursor, or unmark it; None, or why it cannot be marked."""
        row = self._rows.get(self.selected_job or "")
        if row is None or row.section not in MARKABLE:
            what = "no job" if row is None else f"{clean(row.job.job_id, 40)} is {row.job.state}"
            return f"mark: {what}; only waiting jobs can be marked"
        self._set_marks({row.job.job_id}, row.job.job_id not in self._marked)
        return None

    def mark_client(self) -> str:
        """Mark every waiting job of the selected job's client (unmark them if all were)."""
        row = self._rows.get(self.selected_job or "")
        if row is None:
            return "mark: no job selected"
        client = row.job.client_id
        waiting = {
            key
            for key, r in self._rows.items()
            if r.section in MARKABLE and r.job.client_id == client
        }
        if not waiting:
            return f"mark: no waiting job from {clean(client, 40)}"
        mark = not waiting <= self._marked
        self._set_marks(waiting, mark)
        done = "marked" if mark else "unmarked"
        return f"{done} {len(waiting)} waiting job(s) from {clean(client, 40)}"

    def _set_marks(self, job_ids: set[str], mark: bool) -> None:
        self._marked = self._marked | job_ids if mark else self._marked - job_ids
        for key in job_ids:
            cell = row_cells(self._rows[key], mark)[0]
            self._shown[key] = (cell, *self._shown[key][1:])
            self.update_cell(key, "section", cell, update_width=True)
        self._say_marks()

    def _say_marks(self) -> None:
        count = len(self._marked)
        self.border_subtitle = f"{count} marked · R: reject" if count else ""

    def show_rows(self, rows: list[QueueRow]) -> None:
        """Bring the table in line with ``rows``; the cursor stays on the same job if it can,
        or among those awaiting approval (:func:`cursor_after`). Marks of jobs that no longer
        wait are dropped."""
        keys = [row.job.job_id for row in rows]
        previous = [self._rows[k] for k in self._keys if k in self._rows]
        self._rows = {row.job.job_id: row for row in rows}
        self._marked = {
            k for k in self._marked if k in self._rows and self._rows[k].section in MARKABLE
        }
        self._say_marks()
        cells = {row.job.job_id: row_cells(row, row.job.job_id in self._marked) for row in rows}
        if keys == self._keys:
            for key in keys:
                for (column, _), before, after in zip(
                    COLUMNS, self._shown[key], cells[key], strict=True
                ):
                    if before != after:
                        self.update_cell(key, column, after)
            self._shown = cells
            return
        selected = cursor_after(self.selected_job, previous, rows)
        self.clear()
        for key in keys:
            self.add_row(*cells[key], key=key)
        self._keys, self._shown = keys, cells
        if selected in cells:
            self.move_cursor(row=keys.index(selected), animate=False)
        self.post_message(self.JobHighlighted(self.selected_job))

    def on_data_table_row_highlighted(self, event: DataTable.RowHighlighted) -> None:
        event.stop()
        self.post_message(self.JobHighlighted(event.row_key.value))


def cursor_after(selected: str | None, before: list[QueueRow], after: list[QueueRow]) -> str | None:
    """The job the cursor is on once the rows change from ``before`` to ``after``: the same job,
    unless it was awaiting approval and is not any more (approved, rejected): then the job
    awaiting approval now where it was, or the last one still awaiting. So ``a`` three times
    approves the next three submissions, as a mail client's delete moves to the next message."""
    was = [r.job.job_id for r in before if r.section == "awaiting"]
    awaiting = [r.job.job_id for r in after if r.section == "awaiting"]
    if selected not in was or selected in awaiting or not awaiting:
        return selected
    return awaiting[min(was.index(selected), len(awaiting) - 1)]

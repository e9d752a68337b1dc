"""The queue: awaiting approval, queued with ETA, active, done with metrics, failed with reason."""

from __future__ import annotations

from rich.text import Text
from textual.message import Message
from textual.widgets import DataTable

from tui import format as fmt
from tui.rows import QueueRow

COLUMNS = (("section", "State"), ("char", "Char"), ("job", "Job"), ("detail", "Detail"))
"""Job ids before the details, which are the widest: a narrow queue still shows every id."""

Cells = tuple[Text, ...]


def row_cells(row: QueueRow) -> Cells:
    """The cells of one job: Text only, as DataTable reads a ``str`` cell as markup."""
    return (
        fmt.section_text(row),
        Text(fmt.short_id(row.job.label, 12), style="bold"),
        Text(fmt.short_id(row.job.job_id)),
        Text(fmt.job_detail(row)),
    )


class QueueTable(DataTable[Text]):
    """Jobs by section; the cursor selects the job that approve/reject/cancel act on."""

    class JobHighlighted(Message):
        """The cursor moved to another job (or to none)."""

        def __init__(self, job_id: str | None) -> None:
            super().__init__()
            self.job_id = job_id

    def __init__(self, **kwargs: object) -> None:
        super().__init__(cursor_type="row", **kwargs)  # type: ignore[arg-type]
        self._keys: list[str] = []
        self._shown: dict[str, Cells] = {}

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

    def show_rows(self, rows: list[QueueRow]) -> None:
        """Bring the table in line with ``rows``; the cursor stays on the same job if it can."""
        keys = [row.job.job_id for row in rows]
        cells = {row.job.job_id: row_cells(row) for row in rows}
        if keys == self._keys:
            for key in keys:
                for (column, _), before, after in zip(
                    COLUMNS, self._shown[key], cells[key], strict=True
                ):
                    if before != after:
                        self.update_cell(key, column, after)
            self._shown = cells
            return
        selected = self.selected_job
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

"""The console says how much of a cancelled job its vehicle had written (issue 34): the metrics
its ``ended`` report left on the job, before the reason, so that a cut line keeps it."""

from __future__ import annotations

from bus.messages import ErrorInfo, JobMetrics, JobState
from tui.format import DETAIL_CHARS, job_detail
from tui.rows import QueueRow

PART = JobMetrics(
    rmse_pen_down_m=0.004, rmse_m=0.006, max_error_m=0.02, iou=0.31, duration_s=6.0,
    flown_fraction=0.42,
)  # fmt: skip


def _cancelled(metrics: JobMetrics | None, message: str) -> QueueRow:
    job = JobState(
        job_id="j1", state="cancelled", label="十", kind="text", client_id="kiosk",
        created_at_s=0.0, updated_at_s=1.0, metrics=metrics,
        error=ErrorInfo(code="cancelled", message=message),
    )  # fmt: skip
    return QueueRow("failed", job)


def test_a_cancelled_job_says_how_much_was_written_before_its_reason() -> None:
    assert job_detail(_cancelled(PART, "cancelled by operator")) == (
        "42% written; cancelled by operator"
    )
    long = job_detail(_cancelled(PART, "x" * 200))
    assert long.startswith("42% written; x") and len(long) == DETAIL_CHARS
    assert job_detail(_cancelled(None, "cancelled by operator")) == "cancelled by operator"

"""A small preview of the selected submission: its strokes drawn, or its typed text."""

from __future__ import annotations

from typing import Any

from rich.console import Group, RenderableType
from rich.text import Text
from textual.reactive import reactive
from textual.widgets import Static

from bus.messages import JobState
from tui.preview import render_preview
from tui.safe_text import clean


def job_strokes(job: JobState) -> dict[str, Any] | None:
    """The strokes document of a drawn job (the orchestrator sends it while the job waits; the
    console's model keeps it afterwards)."""
    return job.strokes


def job_text(job: JobState) -> str | None:
    text = getattr(job, "text", None)
    if isinstance(text, str) and text:
        return text
    return job.label if job.kind == "text" else None


class PreviewPane(Static):
    """What the selected job will write."""

    job: reactive[JobState | None] = reactive(None)
    """Job under the queue cursor."""

    def render(self) -> RenderableType:
        job = self.job
        if job is None:
            return Text("no job selected", style="dim", justify="center")
        cols = max(4, self.content_size.width)
        rows = max(2, self.content_size.height - 1)
        drawing = render_preview(job_text(job), job_strokes(job), job.label, cols, rows)
        caption = Text(
            f"{job.kind} · {clean(job.client_id, 100)}",
            style="dim",
            justify="center",
            no_wrap=True,
            overflow="ellipsis",
        )
        return Group(drawing, caption)

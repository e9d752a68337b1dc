"""The selected submission's drawing on the whole screen, large enough to judge (``v``)."""

from __future__ import annotations

from typing import ClassVar

from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.screen import ModalScreen
from textual.widgets import Footer

from bus.messages import JobState
from tui.safe_text import plain
from tui.widgets.preview_pane import PreviewPane


class PreviewScreen(ModalScreen[None]):
    """One job's preview filling the terminal; Escape or q goes back."""

    BINDINGS: ClassVar[list[BindingType]] = [Binding("escape,q,v", "app.pop_screen", "back")]

    def __init__(self, job: JobState) -> None:
        super().__init__()
        self.job = job

    def compose(self) -> ComposeResult:
        pane = PreviewPane(id="preview-full")
        pane.job = self.job
        yield pane
        yield Footer()

    def on_mount(self) -> None:
        pane = self.query_one(PreviewPane)
        pane.border_title = plain(
            f"{self.job.label} · {self.job.job_id} · {self.job.state}", max_chars=80
        )

"""A yes/no question in front of everything, for commands that cannot be taken back."""

from __future__ import annotations

from typing import ClassVar

from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.screen import ModalScreen
from textual.widgets import Button, Input, Static

from bus.messages import MAX_TEXT_CHARS


class ConfirmScreen(ModalScreen[str | None]):
    """Dismissed with the reason typed ("" when none) by ``y``, Enter in the reason or the confirm
    button; with None by ``n``, Escape or the cancel button.

    With a reason input, ``y`` and ``n`` are letters of the reason: Enter confirms, Escape cancels.
    """

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("y", "answer(True)", "yes", show=True),
        Binding("n,escape", "answer(False)", "no", show=True),
    ]

    def __init__(
        self, question: str, confirm_label: str = "Yes", *, reason_prompt: str | None = None
    ) -> None:
        super().__init__()
        self.question = question
        """What the operator is asked: plain text, never markup (it may name bus data)."""
        self.confirm_label = confirm_label
        self.reason_prompt = reason_prompt
        """Placeholder of the optional reason input; None: no input."""

    def compose(self) -> ComposeResult:
        with Vertical(id="confirm-dialog"):
            yield Static(Text(self.question), id="confirm-question")
            if self.reason_prompt is not None:
                yield Input(
                    placeholder=self.reason_prompt, max_length=MAX_TEXT_CHARS, id="confirm-reason"
                )
            with Horizontal(id="confirm-buttons"):
                keys = "Enter" if self.reason_prompt is not None else "y"
                yield Button(f"{self.confirm_label} ({keys})", variant="error", id="confirm-yes")
                no = "Esc" if self.reason_prompt is not None else "n"
                yield Button(f"Cancel ({no})", variant="primary", id="confirm-no")

    def on_mount(self) -> None:
        if self.reason_prompt is not None:
            self.query_one("#confirm-reason", Input).focus()
        else:
            self.query_one("#confirm-no", Button).focus()

    @property
    def reason(self) -> str:
        if self.reason_prompt is None:
            return ""
        return self.query_one("#confirm-reason", Input).value.strip()

    def on_input_submitted(self, event: Input.Submitted) -> None:
        event.stop()
        self.dismiss(self.reason)

    def on_button_pressed(self, event: Button.Pressed) -> None:
        event.stop()
        self.dismiss(self.reason if event.button.id == "confirm-yes" else None)

    def action_answer(self, answer: bool) -> None:
        self.dismiss(self.reason if answer else None)

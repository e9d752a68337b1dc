"""One line at the top: show, orchestrator presence, queue state, fleet counts, last answer."""

from __future__ import annotations

from rich.text import Text
from textual.reactive import reactive
from textual.widgets import Static


class HeaderBar(Static):
    """Show-wide status; every field is reactive, so only real changes redraw it."""

    show_id: reactive[str] = reactive("")
    orchestrator: reactive[str] = reactive("unknown")
    """``unknown``, ``online`` or ``offline``."""
    queue_paused: reactive[bool] = reactive(False)
    counts: reactive[str] = reactive("")
    """e.g. ``3 vehicles, 2 writing``."""
    last_reply: reactive[str] = reactive("")
    """The orchestrator's answer to the last command."""
    last_reply_ok: reactive[bool] = reactive(True)

    def watch_orchestrator(self, value: str) -> None:
        self.set_class(value == "offline", "-offline")

    def render(self) -> Text:
        text = Text(no_wrap=True, overflow="ellipsis")
        text.append(" skyquill ", style="bold reverse")
        text.append(f" {self.show_id} ", style="bold")
        if self.orchestrator == "online":
            text.append("● orchestrator ", style="green")
        elif self.orchestrator == "offline":
            text.append("✖ ORCHESTRATOR GONE (last known state) ", style="bold white on red")
        else:
            text.append("? orchestrator ", style="yellow")
        if self.queue_paused:
            text.append("⏸ QUEUE PAUSED ", style="bold black on yellow")
        else:
            text.append("▶ queue ", style="green")
        text.append(self.counts, style="dim")
        if self.last_reply:
            text.append("  » ", style="dim")
            text.append(self.last_reply, style="green" if self.last_reply_ok else "bold red")
        return text

"""One line at the top: show, orchestrator presence, queue state, fleet counts, last answer."""

from __future__ import annotations

from rich.text import Text
from textual.reactive import reactive
from textual.widgets import Static

from tui.safe_text import clean


class HeaderBar(Static):
    """Show-wide status; every field is reactive, so only real changes redraw it."""

    show_id: reactive[str] = reactive("")
    orchestrator: reactive[str] = reactive("unknown")
    """``unknown``, ``online`` or ``offline``."""
    queue_paused: reactive[bool] = reactive(False)
    can_fly: reactive[int] = reactive(1)
    """Vehicles that could take the next job (present, not held, not in fault)."""
    faults: reactive[int] = reactive(0)
    """Vehicles in fault."""
    awaiting: reactive[int] = reactive(0)
    """Submissions awaiting approval."""
    counts: reactive[str] = reactive("")
    """e.g. ``3 vehicles, 2 writing``."""
    last_reply: reactive[str] = reactive("")
    """The orchestrator's answer to the last command."""
    last_reply_ok: reactive[bool] = reactive(True)

    def watch_orchestrator(self, value: str) -> None:
        self.set_class(value == "offline", "-offline")

    def render(self) -> Text:
        """Whole parts only: on a narrow terminal the least urgent ones are left out, none cut."""
        parts = self._parts()
        width = self.content_size.width or 10_000
        while len(parts) > 1 and sum(p.cell_len for _, p in parts) > width:
            parts.remove(min(parts, key=lambda part: part[0]))
        text = Text(no_wrap=True, overflow="ellipsis")
        for _, part in parts:
            text.append_text(part)
        return text

    def _parts(self) -> list[tuple[int, Text]]:
        """``(urgency, text)`` in display order; higher urgency stays longer."""
        parts = [(9, Text(" skyquill ", style="bold reverse"))]
        parts.append((1, Text(f" {clean(self.show_id, 40)} ", style="bold")))
        if self.orchestrator == "online":
            parts.append((5, Text("● orchestrator ", style="green")))
        elif self.orchestrator == "offline":
            parts.append((9, Text("✖ ORCHESTRATOR GONE ", style="bold white on red")))
        else:
            parts.append((5, Text("? orchestrator ", style="yellow")))
        if self.queue_paused:
            parts.append((8, Text("⏸ QUEUE PAUSED ", style="bold black on yellow")))
        elif self.can_fly == 0:
            parts.append((8, Text("⏹ NO VEHICLE CAN FLY ", style="bold black on yellow")))
        else:
            parts.append((6, Text("▶ queue ", style="green")))
        if self.faults:
            parts.append((9, Text(f"✖ {self.faults} fault ", style="bold white on red")))
        if self.awaiting:
            parts.append((7, Text(f"✋ {self.awaiting} to approve ", style="bold black on yellow")))
        parts.append((2, Text(self.counts + " ", style="dim")))
        if self.last_reply:
            style = "green" if self.last_reply_ok else "bold red"
            parts.append(
                (3 if self.last_reply_ok else 4, Text(f"» {clean(self.last_reply)}", style=style))
            )
        return parts

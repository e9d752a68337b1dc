"""Alerts that stand out: lost vehicles, tracking errors over the limit, failed jobs."""

from __future__ import annotations

from rich.text import Text
from textual.reactive import reactive
from textual.widgets import Static

from tui.safe_text import clean


class AlertBar(Static):
    """A red line while there is anything to act on; a quiet one otherwise."""

    alerts: reactive[tuple[str, ...]] = reactive(())
    """Messages of the current, unacknowledged alerts."""

    def watch_alerts(self, alerts: tuple[str, ...]) -> None:
        self.set_class(bool(alerts), "-active")

    def render(self) -> Text:
        if not self.alerts:
            return Text(" no alerts", style="dim", no_wrap=True)
        text = Text(no_wrap=True, overflow="ellipsis")
        text.append(f" ⚠ {len(self.alerts)} ", style="bold reverse")
        text.append(" x:ack ", style="italic")
        width = self.content_size.width or 10_000
        for i, message in enumerate(self.alerts):
            shown = clean(message)
            rest = len(self.alerts) - i
            if text.cell_len + 3 + len(shown) + (6 if rest > 1 else 0) > width:
                text.append(f" │ +{rest} more", style="italic")  # whole alerts only
                break
            if i:
                text.append(" │ ")
            text.append(shown)
        return text

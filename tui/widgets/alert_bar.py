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
        return alert_line(self.alerts, self.content_size.width or 10_000)


def alert_line(alerts: tuple[str, ...], width: int) -> Text:
    """The alert line in ``width`` cells: the count, then the alerts whole, the first always
    shown (cut to fit when it is longer than the line) and ``+N more`` for those left out."""
    if not alerts:
        return Text(" no alerts", style="dim", no_wrap=True)
    text = Text(no_wrap=True, overflow="ellipsis")
    text.append(f" ⚠ {len(alerts)} ", style="bold reverse")
    text.append(" x:ack ", style="italic")
    for i, message in enumerate(alerts):
        shown = Text(clean(message))
        rest = len(alerts) - i
        after = len(_more(rest - 1)) if rest > 1 else 0
        room = width - text.cell_len - (3 if i else 0) - after
        if shown.cell_len > room and i:
            text.append(_more(rest), style="italic")  # whole alerts after the first
            break
        if i:
            text.append(" │ ")
        if shown.cell_len > room:  # the first is always shown, cut to fit
            shown.truncate(max(1, room), overflow="ellipsis")
            text.append_text(shown)
            if rest > 1:
                text.append(_more(rest - 1), style="italic")
            break
        text.append_text(shown)
    return text


def _more(count: int) -> str:
    return f" │ +{count} more"

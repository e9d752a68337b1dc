"""When to redraw: a bounded rate while data changes, a slow pulse while it does not."""

from __future__ import annotations


class RedrawThrottle:
    """Decides when to redraw: at most ``rate_hz`` while data changes, and every ``idle_s`` anyway
    (ages and clocks on screen move even when no message arrives)."""

    def __init__(self, rate_hz: float, idle_s: float = 0.5, slack_s: float = 0.0) -> None:
        if rate_hz <= 0:
            raise ValueError("rate_hz must be > 0")
        self.interval_s = 1.0 / rate_hz
        """Shortest time between two redraws, in [s]."""
        self.slack_s = slack_s
        """Tolerance for a timer that fires a little early (half its period is right), in [s]."""
        self.idle_s = idle_s
        """Longest time between two redraws, in [s]."""
        self._last_s: float | None = None

    def due(self, now_s: float, dirty: bool) -> bool:
        """Whether to redraw now; when True the redraw is counted as done."""
        elapsed = None if self._last_s is None else now_s - self._last_s
        if (
            elapsed is not None
            and elapsed < (self.interval_s if dirty else self.idle_s) - self.slack_s
        ):
            return False
        self._last_s = now_s
        return True

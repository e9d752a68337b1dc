"""A sliding-window rate limiter, pure: the caller passes the time.

The one rule of every service that takes submissions: the kiosk per visitor's address, the
orchestrator per identity on the bus (``rate_limited`` in docs/protocol.md)."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field


@dataclass
class SlidingWindowLimiter:
    """At most ``limit`` events per ``window_s`` seconds for each key.

    Keys are client identities (an address, a certificate's common name). Memory stays bounded:
    once more than ``max_keys`` keys are tracked, keys with no event inside the window are
    forgotten.
    """

    limit: int
    """Events allowed per window per key (>= 1)."""
    window_s: float = 60.0
    """Length of the window in [s]."""
    max_keys: int = 10_000
    """Tracked keys before idle ones are swept."""
    _events: dict[str, deque[float]] = field(default_factory=dict, init=False, repr=False)

    def __post_init__(self) -> None:
        if self.limit < 1 or self.window_s <= 0.0:
            raise ValueError("limit must be >= 1 and window_s > 0")

    def hit(self, key: str, now_s: float) -> float | None:
        """Count an event for ``key`` at ``now_s``; None when allowed, else seconds to wait."""
        events = self._events.get(key)
        if events is None:
            if len(self._events) >= self.max_keys:
                self._sweep(now_s)
            events = self._events[key] = deque()
        while events and events[0] <= now_s - self.window_s:
            events.popleft()
        if len(events) >= self.limit:
            return max(0.0, events[0] + self.window_s - now_s)
        events.append(now_s)
        return None

    def _sweep(self, now_s: float) -> None:
        horizon = now_s - self.window_s
        for key in [k for k, ev in self._events.items() if not ev or ev[-1] <= horizon]:
            del self._events[key]

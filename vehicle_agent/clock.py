"""The agent's time: a fixed-rate tick counter paced against a (scaled) wall clock.

Agent time is ``tick * period_s``: every control period advances it by exactly one period, so the
planned trajectory, the controller and a simulated vehicle stay in lock step however busy the
machine is. The wall clock only paces the loop: with ``time_scale = N`` a tick is due every
``period_s / N`` seconds of wall time. A simulated vehicle never skips a tick (the show just runs
slower than asked when the CPU cannot keep up); a real vehicle lives in real time, so with
``skip_when_late`` the counter jumps ahead to the wall clock after a stall.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field


@dataclass
class TickClock:
    """Which tick is next and when it is due (pure apart from the injected ``wall_s``)."""

    period_s: float
    """Control period in [s] of agent time (0.01 at 100 Hz)."""
    time_scale: float = 1.0
    """Agent seconds per wall second (> 1 runs a simulated show faster than real time)."""
    skip_when_late: bool = False
    """Jump ahead after a stall instead of running the missed ticks back to back."""
    wall_s: Callable[[], float] = time.monotonic
    """The wall clock in [s] (injected so tests can drive it)."""
    tick: int = 0
    """Index of the next tick."""
    _start_wall_s: float = field(default=math.nan, init=False)

    def __post_init__(self) -> None:
        if self.period_s <= 0.0 or self.time_scale <= 0.0:
            raise ValueError("period_s and time_scale must be positive")
        self._start_wall_s = self.wall_s()

    @property
    def now_s(self) -> float:
        """Agent time in [s] of the next tick."""
        return self.tick * self.period_s

    @property
    def wall_period_s(self) -> float:
        """Wall time in [s] between two ticks."""
        return self.period_s / self.time_scale

    def delay_s(self) -> float:
        """Wall time in [s] to wait before the next tick is due (0 when it is due or late)."""
        due = self._start_wall_s + self.tick * self.wall_period_s
        return max(0.0, due - self.wall_s())

    def advance(self) -> None:
        """The tick ran: move to the next one (skipping missed ones when asked)."""
        self.tick += 1
        if self.skip_when_late:
            behind = (self.wall_s() - self._start_wall_s) / self.wall_period_s - self.tick
            if behind > 1.0:
                self.tick += int(behind)

    def catch_up(self) -> None:
        """Bring the next tick up to the wall clock after a rest (agent time went on meanwhile:
        the ticks not run are skipped, whatever ``skip_when_late`` says)."""
        due = math.floor((self.wall_s() - self._start_wall_s) / self.wall_period_s)
        self.tick = max(self.tick, due)

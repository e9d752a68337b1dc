"""How a control loop waits for its next tick: on a timer of its own, or on a timer it shares.

An agent process has one vehicle and sleeps to its own schedule (:class:`OwnTimer`). A fleet host
runs many simulated vehicles in one event loop; giving each awake vehicle its own 100 Hz sleep
would put one timer per vehicle and tick in the loop's heap. :class:`SharedTicker` keeps one
timer for the whole host instead: at every ``period_s`` of wall time one timer callback wakes
every vehicle due by then, and they all run their ticks in that same turn of the loop, the
physics of the host's vehicles stepped together. A vehicle that is behind (its agent clock late
against the wall clock) does not wait for the grid but yields once per tick, so no tick is
skipped and the other vehicles still run; a vehicle on time ticks on the host's grid, at the
instant nearest its own schedule (at most half a period early or late).
"""

from __future__ import annotations

import asyncio
import math
import time
from typing import Protocol


class Pacer(Protocol):
    """Waits until a wall time (``time.monotonic`` seconds) has come."""

    async def wait_until(self, wall_s: float) -> None:
        """Return at ``wall_s`` or soon after (at once when it has passed)."""
        ...


class OwnTimer:
    """One loop, one timer: sleep until the tick is due (a separate agent process)."""

    async def wait_until(self, wall_s: float) -> None:
        await asyncio.sleep(max(0.0, wall_s - time.monotonic()))


class SharedTicker:
    """One timer for every control loop of the host: ticks on a fixed grid of ``period_s``."""

    def __init__(self, period_s: float) -> None:
        if not period_s > 0.0:
            raise ValueError("period_s must be positive")
        self.period_s = period_s
        """Wall time in [s] between two ticks of the grid."""
        self._epoch_s = time.monotonic()
        self._waiters: list[asyncio.Future[None]] = []
        self.ticks = 0
        """How many grid ticks fired (one timer each, whatever the number of vehicles)."""

    async def wait_until(self, wall_s: float) -> None:
        """Wait for the grid instant nearest ``wall_s`` (a tick due just after an instant runs
        at it rather than a whole period later, so intervals stay one period, not 0 and 2).
        A loop already due still yields once: a vehicle behind (its ticks back to back) must not
        hold the event loop, or the other vehicles, heartbeats and commands starve."""
        if time.monotonic() >= wall_s - 0.5 * self.period_s:
            await asyncio.sleep(0)
            return
        while time.monotonic() < wall_s - 0.5 * self.period_s:
            await self._next_tick()

    def _next_tick(self) -> asyncio.Future[None]:
        """A future of the caller's own, resolved at the next instant of the grid (the first
        waiter of an instant sets its timer; a cancelled waiter cancels only its future)."""
        loop = asyncio.get_running_loop()
        if not self._waiters:
            steps = math.floor((loop.time() - self._epoch_s) / self.period_s) + 1
            loop.call_at(self._epoch_s + steps * self.period_s, self._fire)
        waiter: asyncio.Future[None] = loop.create_future()
        self._waiters.append(waiter)
        return waiter

    def _fire(self) -> None:
        self.ticks += 1
        waiters, self._waiters = self._waiters, []
        for waiter in waiters:
            if not waiter.done():
                waiter.set_result(None)

"""How a control loop waits for its next tick: on a timer of its own, or on a timer it shares.

An agent process has one vehicle and sleeps to its own schedule (:class:`OwnTimer`). A fleet host
runs many simulated vehicles in one event loop; giving each awake vehicle its own 100 Hz sleep
would put one timer per vehicle and tick in the loop's heap. :class:`SharedTicker` keeps one
timer for the whole host instead: at every ``period_s`` of wall time one timer callback wakes
every vehicle due by then, and they all run their ticks in that same turn of the loop, the
physics of the host's vehicles stepped together. A vehicle ticks at the grid instant nearest
its own schedule (at most half a period early or late); one whose instant has fired already
(it is behind the host) does not wait but yields once per tick, so no tick is skipped and the
other vehicles still run. A host behind the wall clock as a whole runs its instants back to
back, every vehicle of an instant still woken together.
"""

from __future__ import annotations

import asyncio
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
    """One timer for every control loop of the host: ticks on a fixed grid of ``period_s``.

    A loop waits for the grid instant nearest its due time; every loop of an instant is woken
    by that instant's one timer, in one turn of the event loop, so their vehicles are stepped
    together. Whether a loop is behind is decided by the instant, not by the moment it asks:
    an instant not yet served is waited for (its timer fires at once when its time has passed),
    an instant served already is run at once. So loops of one instant stay together however
    late the host runs: measured by the moment they asked, loops finishing one turn's ticks
    before and after the half-period mark fell into two groups, and the fleet was split into
    two steps at every tick (11 % of an overloaded host's time, ``bench_fleet_host.py``).
    """

    def __init__(self, period_s: float) -> None:
        if not period_s > 0.0:
            raise ValueError("period_s must be positive")
        self.period_s = period_s
        """Wall time in [s] between two ticks of the grid."""
        self._epoch_s = time.monotonic()
        self._waiters: dict[int, list[asyncio.Future[None]]] = {}
        """The loops waiting for each instant (by index on the grid) whose timer is set."""
        self._served = 0
        """The latest instant whose timer fired (the instants up to the epoch count as served)."""
        self.ticks = 0
        """How many grid ticks fired (one timer each, whatever the number of vehicles)."""

    async def wait_until(self, wall_s: float) -> None:
        """Wait for the grid instant nearest ``wall_s`` (a tick due just after an instant runs
        at it rather than a whole period later, so intervals stay one period, not 0 and 2).
        A loop whose instant was served already still yields once: a vehicle behind (its ticks
        back to back) must not hold the event loop, or the other vehicles, heartbeats and
        commands starve."""
        instant = round((wall_s - self._epoch_s) / self.period_s)
        if instant <= self._served:
            await asyncio.sleep(0)
            return
        await self._waiter(instant)

    def _waiter(self, instant: int) -> asyncio.Future[None]:
        """A future of the caller's own, resolved when ``instant`` fires (its first waiter sets
        its timer; a cancelled waiter cancels only its future)."""
        loop = asyncio.get_running_loop()
        waiters = self._waiters.get(instant)
        if waiters is None:
            waiters = self._waiters[instant] = []
            loop.call_at(self._epoch_s + instant * self.period_s, self._fire, instant)
        waiter: asyncio.Future[None] = loop.create_future()
        waiters.append(waiter)
        return waiter

    def _fire(self, instant: int) -> None:
        self.ticks += 1
        self._served = max(self._served, instant)
        for waiter in self._waiters.pop(instant):
            if not waiter.done():
                waiter.set_result(None)

"""The fleet host's shared ticker: one timer wakes every waiting control loop."""

from __future__ import annotations

import asyncio
import time

from vehicle_agent.pacer import SharedTicker


def test_one_timer_per_grid_instant_wakes_every_loop_and_none_too_early() -> None:
    async def main() -> tuple[SharedTicker, list[float], float]:
        ticker = SharedTicker(0.01)
        due_s = time.monotonic() + 0.05
        woke: list[float] = []

        async def loop() -> None:
            await ticker.wait_until(due_s)
            woke.append(time.monotonic())

        await asyncio.gather(*(loop() for _ in range(50)))
        return ticker, woke, due_s

    ticker, woke, due_s = asyncio.run(main())
    assert len(woke) == 50
    assert ticker.ticks <= 7  # one timer per instant up to the due time, not one per loop
    assert min(woke) >= due_s - 0.5 * ticker.period_s  # the grid instant nearest the due time


def test_a_cancelled_loop_does_not_cancel_the_others() -> None:
    async def main() -> bool:
        ticker = SharedTicker(0.01)
        due_s = time.monotonic() + 0.03
        leaving = asyncio.create_task(ticker.wait_until(due_s))
        staying = asyncio.create_task(ticker.wait_until(due_s))
        await asyncio.sleep(0)
        leaving.cancel()
        await staying
        return leaving.cancelled()

    assert asyncio.run(main())


def test_loops_behind_their_schedule_take_turns_instead_of_holding_the_event_loop() -> None:
    async def main() -> list[str]:
        ticker = SharedTicker(0.01)
        order: list[str] = []

        async def behind(name: str) -> None:
            for _ in range(3):
                await ticker.wait_until(0.0)  # long past due: ticks back to back
                order.append(name)

        await asyncio.gather(behind("a"), behind("b"))
        return order

    assert asyncio.run(main()) == ["a", "b", "a", "b", "a", "b"]


def test_loops_of_one_instant_wake_together_however_late_in_the_period_they_ask() -> None:
    """A loop asking past the half-period mark (its host busy) still waits for its instant with
    the others, rather than running alone: otherwise the fleet is split at every tick."""

    async def main() -> tuple[float, list[float]]:
        ticker = SharedTicker(0.1)
        await ticker.wait_until(time.monotonic() + 0.1)  # on the grid: an instant just fired
        due_s = time.monotonic() + ticker.period_s  # the next instant
        woke: list[float] = []

        async def early() -> None:
            await ticker.wait_until(due_s)
            woke.append(time.monotonic())

        async def late() -> None:
            while time.monotonic() < due_s - 0.4 * ticker.period_s:  # busy past the mark
                pass
            await ticker.wait_until(due_s)
            woke.append(time.monotonic())

        await asyncio.gather(early(), late())
        return due_s, woke

    due_s, woke = asyncio.run(main())
    assert min(woke) >= due_s - 0.02  # both at the instant (the timer's own latency aside)
    assert max(woke) - min(woke) < 0.01  # in one turn

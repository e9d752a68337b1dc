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

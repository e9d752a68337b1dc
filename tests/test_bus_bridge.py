"""bus.bridge: thread -> asyncio channels with drop-oldest and FIFO policies."""

from __future__ import annotations

import asyncio
import threading

import pytest
from hypothesis import given
from hypothesis import strategies as st

from bus.bridge import ChannelClosedError, FifoChannel, LatestByKey, RingChannel


def _push_from_threads(push: object, items: list[int], n_threads: int) -> None:
    chunks = [items[i::n_threads] for i in range(n_threads)]

    def work(chunk: list[int]) -> None:
        for item in chunk:
            push(item)  # type: ignore[operator]

    threads = [threading.Thread(target=work, args=(c,)) for c in chunks]
    for t in threads:
        t.start()
    for t in threads:
        t.join()


def test_fifo_never_drops_items_pushed_from_other_threads() -> None:
    async def main() -> list[int]:
        channel: FifoChannel[int] = FifoChannel()
        items = list(range(5000))
        await asyncio.to_thread(_push_from_threads, channel.push, items, 4)
        channel.close()
        return [item async for item in channel]

    got = asyncio.run(main())
    assert sorted(got) == list(range(5000))


def test_fifo_keeps_order_from_one_thread() -> None:
    async def main() -> list[int]:
        channel: FifoChannel[int] = FifoChannel()
        await asyncio.to_thread(_push_from_threads, channel.push, list(range(1000)), 1)
        channel.close()
        return [item async for item in channel]

    assert asyncio.run(main()) == list(range(1000))


@given(st.integers(1, 20), st.lists(st.integers(), max_size=60))
def test_ring_keeps_the_newest_and_counts_drops(maxlen: int, items: list[int]) -> None:
    async def main() -> tuple[list[int], int]:
        channel: RingChannel[int] = RingChannel(maxlen)
        for item in items:
            channel.push(item)
        return channel.drain(), channel.dropped

    kept, dropped = asyncio.run(main())
    assert kept == items[-maxlen:] if items else kept == []
    assert dropped == max(0, len(items) - maxlen)


def test_get_waits_for_a_push_from_another_thread_and_close_ends_iteration() -> None:
    async def main() -> tuple[int, bool]:
        channel: RingChannel[int] = RingChannel(4)
        waiter = asyncio.create_task(channel.get())
        await asyncio.sleep(0)
        threading.Thread(target=channel.push, args=(42,)).start()
        value = await asyncio.wait_for(waiter, 5.0)
        channel.close()
        try:
            await channel.get()
        except ChannelClosedError:
            return value, True
        return value, False

    assert asyncio.run(main()) == (42, True)


def test_cancelled_getter_does_not_swallow_the_next_item() -> None:
    async def main() -> int:
        channel: FifoChannel[int] = FifoChannel()
        first = asyncio.create_task(channel.get())
        await asyncio.sleep(0)
        first.cancel()
        second = asyncio.create_task(channel.get())
        await asyncio.sleep(0)
        channel.push(7)
        return await asyncio.wait_for(second, 5.0)

    assert asyncio.run(main()) == 7


def test_latest_by_key_merges_updates() -> None:
    async def main() -> tuple[dict[str, int], dict[str, int], int]:
        latest: LatestByKey[str, int] = LatestByKey()
        await asyncio.to_thread(
            lambda: [latest.push(k, i) for i, k in enumerate(["a", "b", "a", "a"])]
        )
        first = await asyncio.wait_for(latest.take(), 5.0)
        latest.push("b", 9)
        second = latest.take_nowait()
        return first, second, latest.replaced

    first, second, replaced = asyncio.run(main())
    assert first == {"a": 3, "b": 1}
    assert second == {"b": 9}
    assert replaced == 2


def test_latest_by_key_wakes_the_loop_only_for_a_waiting_reader() -> None:
    async def main() -> tuple[int, dict[int, int], int]:
        latest: LatestByKey[int, int] = LatestByKey()
        wakes: list[object] = []
        call = latest._call
        latest._call = lambda fn, *args: (wakes.append(fn), call(fn, *args))[1]  # type: ignore[method-assign]
        # nobody waits: a thousand pushes from Zenoh's threads cost the loop nothing
        await asyncio.to_thread(lambda: [latest.push(k % 10, k) for k in range(1000)])
        unwoken = len(wakes)
        assert len(latest.take_nowait()) == 10
        # a reader waits: the next push from another thread wakes it, once
        reader = asyncio.create_task(latest.take())
        await asyncio.sleep(0.01)
        await asyncio.to_thread(lambda: [latest.push(k, 100 + k) for k in range(3)])
        taken = await asyncio.wait_for(reader, 5.0)
        return unwoken, taken, len(wakes)

    unwoken, taken, woken = asyncio.run(main())
    assert unwoken == 0
    assert taken and all(item == 100 + key for key, item in taken.items())
    assert woken == 1


def test_channel_outside_a_loop_needs_an_explicit_loop() -> None:
    with pytest.raises(RuntimeError, match="event loop"):
        FifoChannel()


def test_latest_by_key_under_concurrent_pushes_keeps_order_and_the_newest_per_key() -> None:
    """Four threads (Zenoh's, in a show) push 2,000 numbered items each on two keys of their own
    while a reader takes as fast as it can: per key the items taken only go forward, the last
    one pushed is always taken, and every push is either taken or counted as replaced."""
    per_thread, keys_per_thread, threads = 2000, 2, 4

    async def main() -> tuple[dict[str, list[int]], int]:
        latest: LatestByKey[str, int] = LatestByKey()
        taken: dict[str, list[int]] = {}

        def work(t: int) -> None:
            for n in range(per_thread):
                latest.push(f"t{t}k{n % keys_per_thread}", n)

        async def read() -> None:
            while True:
                for key, item in (await latest.take()).items():
                    taken.setdefault(key, []).append(item)

        reader = asyncio.create_task(read())
        await asyncio.gather(*(asyncio.to_thread(work, t) for t in range(threads)))
        await asyncio.sleep(0.05)  # the reader takes what the last pushes left
        reader.cancel()
        for key, item in latest.take_nowait().items():
            taken.setdefault(key, []).append(item)
        return taken, latest.replaced

    taken, replaced = asyncio.run(main())
    assert len(taken) == threads * keys_per_thread
    for key, items in taken.items():
        assert items == sorted(set(items)), key
        assert items[-1] == per_thread - keys_per_thread + int(key[-1])
    assert sum(map(len, taken.values())) + replaced == threads * per_thread

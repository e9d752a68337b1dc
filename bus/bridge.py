"""From Zenoh's threads to asyncio: channels with an explicit overflow policy.

Zenoh runs callbacks on its own threads. A channel is created inside the event loop (or given the
loop), fed from any thread with :meth:`push` (``loop.call_soon_threadsafe`` underneath) and read
in the loop with ``await channel.get()`` or ``async for item in channel``.

- :class:`RingChannel`: bounded, drops the OLDEST item when full (telemetry: only the newest
  matters); ``dropped`` counts what was lost.
- :class:`FifoChannel`: unbounded, never drops (commands, reports, submissions).
- :class:`LatestByKey`: keeps only the newest item per key and hands out what changed since the
  last take (merging telemetry of many vehicles before it reaches a display).
"""

from __future__ import annotations

import asyncio
import threading
from collections import deque
from collections.abc import Hashable
from typing import Generic, TypeVar

T = TypeVar("T")
K = TypeVar("K", bound=Hashable)


class ChannelClosedError(Exception):
    """The channel was closed and holds no more items."""


def _resolve_loop(loop: asyncio.AbstractEventLoop | None) -> asyncio.AbstractEventLoop:
    if loop is not None:
        return loop
    try:
        return asyncio.get_running_loop()
    except RuntimeError:
        raise RuntimeError(
            "create bridge channels inside a running event loop or pass loop="
        ) from None


class _LoopBound:
    """Runs mutations on the loop's thread, whichever thread asks."""

    def __init__(self, loop: asyncio.AbstractEventLoop | None) -> None:
        self._loop = _resolve_loop(loop)
        self.lost_after_loop_closed = 0
        """Items pushed after the event loop had closed (nothing could receive them)."""

    def _in_loop_thread(self) -> bool:
        try:
            return asyncio.get_running_loop() is self._loop
        except RuntimeError:
            return False

    def _call(self, fn: object, *args: object) -> None:
        if self._in_loop_thread():
            fn(*args)  # type: ignore[operator]
            return
        try:
            self._loop.call_soon_threadsafe(fn, *args)  # type: ignore[arg-type]
        except RuntimeError:  # loop closed: the consumer is gone
            self.lost_after_loop_closed += 1


class _Channel(_LoopBound, Generic[T]):
    def __init__(self, loop: asyncio.AbstractEventLoop | None, maxlen: int | None) -> None:
        super().__init__(loop)
        if maxlen is not None and maxlen < 1:
            raise ValueError("maxlen must be >= 1")
        self._items: deque[T] = deque()
        self._maxlen = maxlen
        self._waiters: deque[asyncio.Future[None]] = deque()
        self._closed = False
        self.dropped = 0
        """Items discarded because the channel was full."""

    def push(self, item: T) -> None:
        """Add an item; safe from any thread (Zenoh callbacks)."""
        self._call(self._put, item)

    def close(self) -> None:
        """No more items; readers get what is left, then :class:`ChannelClosedError`."""
        self._call(self._close)

    def _put(self, item: T) -> None:
        if self._closed:
            return
        if self._maxlen is not None and len(self._items) >= self._maxlen:
            self._items.popleft()
            self.dropped += 1
        self._items.append(item)
        self._wake()

    def _close(self) -> None:
        self._closed = True
        self._wake(all_waiters=True)

    def _wake(self, *, all_waiters: bool = False) -> None:
        while self._waiters:
            fut = self._waiters.popleft()
            if not fut.done():
                fut.set_result(None)
                if not all_waiters:
                    return

    def __len__(self) -> int:
        return len(self._items)

    @property
    def closed(self) -> bool:
        return self._closed

    def drain(self) -> list[T]:
        """Every item held now, oldest first (loop thread)."""
        items = list(self._items)
        self._items.clear()
        return items

    async def get(self) -> T:
        """Wait for the oldest item; raises :class:`ChannelClosedError` when closed and empty."""
        while not self._items:
            if self._closed:
                raise ChannelClosedError
            fut: asyncio.Future[None] = self._loop.create_future()
            self._waiters.append(fut)
            try:
                await fut
            except asyncio.CancelledError:
                if fut in self._waiters:
                    self._waiters.remove(fut)
                raise
        item = self._items.popleft()
        if self._items:
            self._wake()
        return item

    def __aiter__(self) -> _Channel[T]:
        return self

    async def __anext__(self) -> T:
        try:
            return await self.get()
        except ChannelClosedError:
            raise StopAsyncIteration from None


class RingChannel(_Channel[T]):
    """Bounded; drops the oldest item when full (telemetry)."""

    def __init__(self, maxlen: int = 64, *, loop: asyncio.AbstractEventLoop | None = None) -> None:
        super().__init__(loop, maxlen)


class FifoChannel(_Channel[T]):
    """Unbounded; never drops (commands, reports, submissions)."""

    def __init__(self, *, loop: asyncio.AbstractEventLoop | None = None) -> None:
        super().__init__(loop, None)


class LatestByKey(_LoopBound, Generic[K, T]):
    """Newest item per key; :meth:`take` returns what changed since the previous take.

    A push from another thread wakes the loop only when a reader is waiting: one that takes at
    intervals (the orchestrator: every 50 ms) costs no turn of the loop per item, where 250
    vehicles' statuses and telemetry are about 900 items a second.
    """

    def __init__(self, *, loop: asyncio.AbstractEventLoop | None = None) -> None:
        super().__init__(loop)
        self._lock = threading.Lock()
        self._latest: dict[K, T] = {}
        self._changed: dict[K, T] = {}
        self._event = asyncio.Event()
        self._reader_waiting = False
        self.replaced = 0
        """Items overwritten by a newer one before anybody took them."""

    def push(self, key: K, item: T) -> None:
        """Record the newest item for ``key``; safe from any thread."""
        with self._lock:
            if key in self._changed:
                self.replaced += 1
            self._latest[key] = item
            self._changed[key] = item
            wake, self._reader_waiting = self._reader_waiting, False
        if wake:
            self._call(self._event.set)

    def latest(self) -> dict[K, T]:
        """Newest item of every key seen so far."""
        with self._lock:
            return dict(self._latest)

    def take_nowait(self) -> dict[K, T]:
        """Items changed since the previous take (possibly empty)."""
        with self._lock:
            changed, self._changed = self._changed, {}
        return changed

    async def take(self) -> dict[K, T]:
        """Wait until something changed, then return the changed items (loop thread)."""
        while True:
            with self._lock:
                if self._changed:
                    changed, self._changed = self._changed, {}
                    self._reader_waiting = False
                    return changed
                self._reader_waiting = True
                self._event.clear()
            await self._event.wait()

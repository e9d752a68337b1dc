"""Thread-safe hand-over of bus messages from Zenoh's threads to the console's event loop.

Zenoh callbacks :meth:`Inbox.put` items; the first item into an empty inbox asks the caller to wake
the consumer (one ``post_message`` per batch, not per message), which then :meth:`Inbox.drain` s
everything at once. Telemetry is bounded and drops the oldest sample when the console falls behind;
everything else (jobs, events, presence) is never dropped. Arrival order is kept across both.
"""

from __future__ import annotations

import heapq
import threading
from collections import deque
from collections.abc import Callable
from typing import Generic, TypeVar

T = TypeVar("T")


class Inbox(Generic[T]):
    """Two queues behind one lock: a bounded drop-oldest one and an unbounded FIFO."""

    def __init__(self, is_droppable: Callable[[T], bool], max_droppable: int = 10_000) -> None:
        if max_droppable < 1:
            raise ValueError("max_droppable must be >= 1")
        self._is_droppable = is_droppable
        self._lock = threading.Lock()
        self._seq = 0
        self._ring: deque[tuple[int, T]] = deque(maxlen=max_droppable)
        self._fifo: deque[tuple[int, T]] = deque()
        self.dropped = 0
        """Droppable items discarded because the consumer was behind."""

    def put(self, item: T) -> bool:
        """Add an item from any thread; True when the inbox was empty (wake the consumer)."""
        droppable = self._is_droppable(item)
        with self._lock:
            was_empty = not self._ring and not self._fifo
            self._seq += 1
            if droppable:
                if len(self._ring) == self._ring.maxlen:
                    self.dropped += 1
                self._ring.append((self._seq, item))
            else:
                self._fifo.append((self._seq, item))
        return was_empty

    def drain(self) -> list[T]:
        """Every waiting item in arrival order; the inbox is empty afterwards."""
        with self._lock:
            ring, fifo = list(self._ring), list(self._fifo)
            self._ring.clear()
            self._fifo.clear()
        return [item for _, item in heapq.merge(ring, fifo, key=lambda pair: pair[0])]

    def __len__(self) -> int:
        with self._lock:
            return len(self._ring) + len(self._fifo)

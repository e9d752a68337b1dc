"""Replies to queries sent from an event loop, collected by one poller per loop.

Zenoh's Python callbacks are the obvious way to hear replies without blocking, but its default
(indirect) callback starts a Python thread per query to run them: in a fleet host whose writing
vehicles each send a report every 0.5 s that was 3-7 % of the host's samples (``Thread.start``,
the interpreter's shutdown-lock list), and the event loop waited for each thread to start. Two
ways round it were measured and dropped (``docs/fleet_host_measurements.md``): callbacks on
Zenoh's own threads (``indirect=False``), which then waited for the interpreter lock; and
sending the queries from one helper thread.

Here each query's replies go into a Zenoh FIFO channel, filled by Zenoh's threads in Rust
without the interpreter lock, and one timer of the event loop, every :data:`POLL_PERIOD_S` while
any query is pending, takes what every pending query has received. A query is over when its
channel closes (after its last reply, or at its timeout): its future then gets the replies.
A reply waits at most one poll period longer than a callback would have made it wait.
"""

from __future__ import annotations

import asyncio
import weakref
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import zenoh

POLL_PERIOD_S = 0.002
"""Wall time in [s] between two polls of the pending queries (only while there are some)."""
CHANNEL_CAPACITY = 256
"""Replies a query's channel holds before Zenoh's thread waits for the poller to take them."""


@dataclass
class _Pending:
    replies_channel: Any
    """The query's Zenoh handler (``try_recv``)."""
    decode: Callable[[zenoh.Reply], Any]
    done: asyncio.Future[list[Any]]
    replies: list[Any] = field(default_factory=list)


class ReplyPoller:
    """The pending queries of one event loop, polled on one timer."""

    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        self._loop = loop
        self._pending: list[_Pending] = []
        self._armed = False

    def get(
        self,
        session: zenoh.Session,
        key_expr: str,
        decode: Callable[[zenoh.Reply], Any],
        **kwargs: Any,
    ) -> asyncio.Future[list[Any]]:
        """Send the query; the future gets every reply, decoded, once the query is over."""
        channel = session.get(key_expr, zenoh.handlers.FifoChannel(CHANNEL_CAPACITY), **kwargs)
        done: asyncio.Future[list[Any]] = self._loop.create_future()
        self._pending.append(_Pending(channel, decode, done))
        if not self._armed:
            self._armed = True
            self._loop.call_later(POLL_PERIOD_S, self._poll)
        return done

    def _poll(self) -> None:
        waiting: list[_Pending] = []
        for pending in self._pending:
            if pending.done.done():  # its caller was cancelled: the channel closes at timeout
                continue
            try:
                while (reply := pending.replies_channel.try_recv()) is not None:
                    pending.replies.append(pending.decode(reply))
            except zenoh.ZError:  # empty and closed: the query is over
                pending.done.set_result(pending.replies)
            except Exception as exc:  # that query's caller hears it; the others go on
                pending.done.set_exception(exc)
            else:
                waiting.append(pending)
        self._pending = waiting
        self._armed = bool(waiting)
        if waiting:
            self._loop.call_later(POLL_PERIOD_S, self._poll)


_POLLERS: weakref.WeakKeyDictionary[asyncio.AbstractEventLoop, ReplyPoller] = (
    weakref.WeakKeyDictionary()
)


def reply_poller() -> ReplyPoller:
    """The running event loop's poller (made on first use)."""
    loop = asyncio.get_running_loop()
    poller = _POLLERS.get(loop)
    if poller is None:
        poller = _POLLERS[loop] = ReplyPoller(loop)
    return poller

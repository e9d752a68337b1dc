"""Publishing, subscribing and presence with typed messages (no raw Zenoh outside bus/).

Callbacks run on Zenoh's threads: keep them short, and hand data to asyncio through a channel
from :mod:`bus.bridge` (``lambda key, msg: ring.push((key, msg))``).
"""

from __future__ import annotations

import contextlib
import itertools
import logging
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar, Literal, TypeVar

import msgspec
import zenoh

from bus.codec import MessageError, decode, encode

M = TypeVar("M", bound=msgspec.Struct)

log = logging.getLogger(__name__)

JSON = zenoh.Encoding.APPLICATION_JSON

Subscriber = zenoh.Subscriber


@dataclass(frozen=True)
class RawSample:
    """A sample as bytes, for recorders and bridges that do not decode."""

    key: str
    """Concrete key expression the sample was published on."""
    payload: bytes
    """Payload bytes (JSON for skyquill messages; empty for deletes)."""
    kind: Literal["put", "delete"]
    """``put`` for data, ``delete`` for a removal (or a liveliness token going away)."""


def _raw(sample: zenoh.Sample) -> RawSample:
    kind: Literal["put", "delete"] = "put" if sample.kind == zenoh.SampleKind.PUT else "delete"
    return RawSample(str(sample.key_expr), sample.payload.to_bytes(), kind)


def publish(session: zenoh.Session, key: str, message: msgspec.Struct) -> None:
    """Publish one message as JSON on ``key``."""
    session.put(key, encode(message), encoding=JSON)


class MessagePublisher:
    """A declared publisher for a key that is written often (telemetry)."""

    def __init__(self, session: zenoh.Session, key: str, *, express: bool = False) -> None:
        self.key = key
        self._publisher = session.declare_publisher(key, encoding=JSON, express=express)

    def put(self, message: msgspec.Struct) -> None:
        """Publish one message."""
        self._publisher.put(encode(message))

    def undeclare(self) -> None:
        self._publisher.undeclare()  # type: ignore[no-untyped-call]


def _guarded(fn: Callable[[zenoh.Sample], None]) -> Callable[[zenoh.Sample], None]:
    def callback(sample: zenoh.Sample) -> None:
        try:
            fn(sample)
        except Exception:  # a callback must never kill Zenoh's thread
            log.exception("subscriber callback failed on %s", sample.key_expr)

    return callback


def _as_raw(fn: Callable[[RawSample], None]) -> Callable[[zenoh.Sample], None]:
    return _guarded(lambda sample: fn(_raw(sample)))


def subscribe_raw(
    session: zenoh.Session, key_expr: str, on_sample: Callable[[RawSample], None]
) -> zenoh.Subscriber[None]:
    """Every sample on ``key_expr`` (wildcards allowed), undecoded."""
    return session.declare_subscriber(key_expr, _as_raw(on_sample))


def subscribe(
    session: zenoh.Session,
    key_expr: str,
    message_type: type[M],
    on_message: Callable[[str, M], None],
    *,
    on_error: Callable[[str, MessageError], None] | None = None,
) -> zenoh.Subscriber[None]:
    """Decoded messages on ``key_expr``; undecodable payloads go to ``on_error`` (or a log line).

    Decoded on Zenoh's callback thread straight from the sample (no :class:`RawSample` in
    between): telemetry of 250 vehicles is 5,000 samples a second, each holding the GIL that the
    event loop also needs; a Telemetry sample took 7.4-8.2 us here, 9.5-12.1 us with one (timeit,
    shared 2-core machine at load 14; ``benchmarks/bench_bus.py`` times the whole path)."""
    put = zenoh.SampleKind.PUT

    def handle(sample: zenoh.Sample) -> None:
        if sample.kind != put:
            return
        key = str(sample.key_expr)
        try:
            message = decode(sample.payload.to_bytes(), message_type)
        except MessageError as exc:
            if on_error is not None:
                on_error(key, exc)
            else:
                log.warning("undecodable %s on %s: %s", message_type.__name__, key, exc)
            return
        on_message(key, message)

    return session.declare_subscriber(key_expr, _guarded(handle))


# --- presence -----------------------------------------------------------------------------------


class Token:
    """A liveliness token that stays declared until :meth:`undeclare` or the session closes.

    (A bare zenoh token is undeclared as soon as Python drops it, which is easy to do by
    accident: ``declare_token(session, key)`` without keeping the result.)
    """

    _lock = threading.Lock()
    _held: ClassVar[dict[int, zenoh.LivelinessToken]] = {}
    _counter = itertools.count()

    def __init__(self, token: zenoh.LivelinessToken, key: str) -> None:
        self.key = key
        self._id = next(Token._counter)
        with Token._lock:
            Token._held[self._id] = token

    def undeclare(self) -> None:
        """Withdraw the token: watchers see the key go away."""
        with Token._lock:
            token = Token._held.pop(self._id, None)
        if token is not None:
            with contextlib.suppress(Exception):  # the session may already be closed
                token.undeclare()  # type: ignore[no-untyped-call]

    def __enter__(self) -> Token:
        return self

    def __exit__(self, *_: object) -> None:
        self.undeclare()


def declare_token(session: zenoh.Session, key: str) -> Token:
    """Announce presence on ``key`` until the token is undeclared or the session closes."""
    return Token(session.liveliness().declare_token(key), key)


def watch_liveliness(
    session: zenoh.Session,
    key_expr: str,
    on_change: Callable[[str, bool], None],
    *,
    history: bool = True,
) -> zenoh.Subscriber[None]:
    """Call ``on_change(key, alive)`` when a token matching ``key_expr`` appears or goes.

    With ``history`` the tokens alive at declaration are reported first (as appearing). Only
    transitions are reported: Zenoh may announce a token twice (history racing the live update).
    """
    alive: set[str] = set()
    lock = threading.Lock()

    def handle(sample: RawSample) -> None:
        now_alive = sample.kind == "put"
        with lock:
            if (sample.key in alive) == now_alive:
                return
            if now_alive:
                alive.add(sample.key)
            else:
                alive.discard(sample.key)
        on_change(sample.key, now_alive)

    return session.liveliness().declare_subscriber(key_expr, _as_raw(handle), history=history)


def watch_router_link(
    session: zenoh.Session, on_change: Callable[[bool], None]
) -> zenoh.TransportEventsListener[None]:
    """Call ``on_change(up)`` when this session's last link to a router goes (``False``) and
    when one opens again (``True``): a router restart, or a cut, seen from this process. Not
    called for a session that is itself the router."""
    routers: set[str] = set()
    lock = threading.Lock()

    def handle(event: zenoh.TransportEvent) -> None:
        if event.transport.whatami != zenoh.WhatAmI.ROUTER:
            return
        zid, up = str(event.transport.zid), event.kind == zenoh.SampleKind.PUT
        with lock:
            had = bool(routers)
            if up:
                routers.add(zid)
            else:
                routers.discard(zid)
            changed = had != bool(routers)
        if changed:
            on_change(up)

    def callback(event: zenoh.TransportEvent) -> None:
        try:
            handle(event)
        except Exception:  # a callback must never kill Zenoh's thread
            log.exception("router link callback failed")

    return session.info.declare_transport_events_listener(callback, history=True)


def alive_keys(session: zenoh.Session, key_expr: str, *, timeout_s: float = 1.0) -> set[str]:
    """Keys of the liveliness tokens matching ``key_expr`` alive now."""
    keys: set[str] = set()
    for reply in session.liveliness().get(key_expr, timeout=timeout_s):
        if reply.ok is not None:
            keys.add(str(reply.ok.key_expr))
    return keys

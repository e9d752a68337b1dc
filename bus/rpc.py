"""Request/reply over Zenoh queries with typed messages.

A service declares a queryable with :func:`serve` (handler on Zenoh's thread) or
:func:`serve_async` (handler in the asyncio loop). The request is decoded before the handler sees
it; a payload that is not a valid request (whatever its bytes: bad JSON or UTF-8, larger than
:func:`bus.codec.request_limit`, too deep, wrong types) gets an error reply (``on_error(info)``
when given, otherwise a Zenoh error reply whose payload is an ErrorInfo) and the handler never
runs. A handler that raises, or whose reply cannot be encoded, produces an ``internal`` error
reply. Every query gets exactly one reply and the queryable keeps serving.

Clients call :func:`query` / :func:`aquery` (all replies, decoded) or :func:`query_one` /
:func:`aquery_one` (first good reply or an exception).
"""

from __future__ import annotations

import functools
import logging
import re
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Generic, TypeVar, overload

import msgspec
import zenoh

from bus.codec import MessageError, check_size, decode, encode, request_limit
from bus.messages import ErrorInfo, Request
from bus.session import BusError

if TYPE_CHECKING:  # imported where used: a blocking client (skyquill status) needs no event loop
    import asyncio

M = TypeVar("M", bound=msgspec.Struct)
R = TypeVar("R", bound=msgspec.Struct)

log = logging.getLogger(__name__)

JSON = zenoh.Encoding.APPLICATION_JSON
DEFAULT_TIMEOUT_S = 2.0

Queryable = zenoh.Queryable

NOT_THE_SERVICES = "remote_error"
"""The code of an error reply whose payload is no ErrorInfo. Every skyquill service answers with
an ErrorInfo, so such a reply is not the service's answer: it is Zenoh's own (a router's
"Timeout" for a query that outlived a link, found when a partition healed) or a stranger's, and
a caller is told there was no reply (:class:`NoReplyError`), never that the service refused."""


class NoReplyError(BusError, TimeoutError):
    """The service did not answer before the timeout (at most Zenoh itself did, see
    :data:`NOT_THE_SERVICES`)."""


class RemoteError(BusError):
    """The queryable answered with an error; ``info`` says what."""

    def __init__(self, info: ErrorInfo) -> None:
        self.info = info
        super().__init__(f"{info.code}: {info.message}")


@dataclass(frozen=True)
class QueryReply(Generic[M]):
    """One reply to a query: a decoded message, or what went wrong."""

    key: str | None
    """Key expression the reply came on (None for error replies)."""
    value: M | None
    """The decoded reply; None when ``error`` is set."""
    error: ErrorInfo | None
    """Error reply from the queryable, or why the reply could not be decoded."""


_CODE = re.compile(r"[a-z][a-z0-9_]{0,63}")
"""What a stable error code looks like: short snake_case."""


def error_info_from_exception(exc: BaseException, *, default_code: str = "internal") -> ErrorInfo:
    """ErrorInfo of an exception, keeping ``stroke_index``/``point_index``/``field`` if set.

    The code is the exception's ``code`` attribute when it is a snake_case word (e.g.
    ``plan_failed`` for a planner error), otherwise ``default_code``: never a class name.
    """
    if isinstance(exc, MessageError):
        return exc.info
    code = getattr(exc, "code", None)
    field = getattr(exc, "field", None)
    stroke_index = getattr(exc, "stroke_index", None)
    point_index = getattr(exc, "point_index", None)
    return ErrorInfo(
        code=code if isinstance(code, str) and _CODE.fullmatch(code) else default_code,
        message=str(exc) or type(exc).__name__,
        field=field if isinstance(field, str) else None,
        stroke_index=stroke_index if type(stroke_index) is int else None,
        point_index=point_index if type(point_index) is int else None,
    )


def _decode_reply(reply: zenoh.Reply, reply_type: type[M]) -> QueryReply[M]:
    ok = reply.ok
    if ok is not None:
        key = str(ok.key_expr)
        try:
            return QueryReply(key, decode(ok.payload.to_bytes(), reply_type), None)
        except MessageError as exc:
            return QueryReply(key, None, exc.info)
    err = reply.err
    raw = err.payload.to_bytes() if err is not None else b""
    try:
        info = decode(raw, ErrorInfo)
    except MessageError:
        info = ErrorInfo(code=NOT_THE_SERVICES, message=raw.decode("utf-8", "replace") or "error")
    return QueryReply(None, None, info)


def _payload(request: msgspec.Struct | bytes | None) -> bytes | None:
    if request is None or isinstance(request, bytes):
        return request
    return encode(request)


def query(
    session: zenoh.Session,
    key_expr: str,
    request: msgspec.Struct | bytes | None,
    reply_type: type[M],
    *,
    timeout_s: float = DEFAULT_TIMEOUT_S,
) -> list[QueryReply[M]]:
    """Send ``request`` (a message, raw bytes, or nothing) and collect every reply (blocking)."""
    payload = _payload(request)
    kwargs: dict[str, Any] = {"timeout": timeout_s}
    if payload is not None:
        kwargs.update(payload=payload, encoding=JSON)
    return [_decode_reply(r, reply_type) for r in session.get(key_expr, **kwargs)]


def _first(replies: list[QueryReply[M]], key_expr: str) -> M:
    for reply in replies:
        if reply.value is not None:
            return reply.value
    for reply in replies:
        if reply.error is not None and reply.error.code != NOT_THE_SERVICES:
            raise RemoteError(reply.error)
    why = "; ".join(r.error.message for r in replies if r.error is not None)
    raise NoReplyError(f"no reply on {key_expr}" + (f" (only: {why})" if why else ""))


def query_one(
    session: zenoh.Session,
    key_expr: str,
    request: msgspec.Struct | bytes | None,
    reply_type: type[M],
    *,
    timeout_s: float = DEFAULT_TIMEOUT_S,
) -> M:
    """The first decoded reply; :class:`NoReplyError` or :class:`RemoteError` otherwise."""
    return _first(query(session, key_expr, request, reply_type, timeout_s=timeout_s), key_expr)


async def aquery(
    session: zenoh.Session,
    key_expr: str,
    request: msgspec.Struct | bytes | None,
    reply_type: type[M],
    *,
    timeout_s: float = DEFAULT_TIMEOUT_S,
) -> list[QueryReply[M]]:
    """:func:`query` without blocking the event loop (replies collected by the loop's
    :class:`bus.reply_poll.ReplyPoller`, not by a thread per query)."""
    from bus.reply_poll import reply_poller

    payload = _payload(request)
    kwargs: dict[str, Any] = {"timeout": timeout_s}
    if payload is not None:
        kwargs.update(payload=payload, encoding=JSON)
    decode = functools.partial(_decode_reply, reply_type=reply_type)
    return await reply_poller().get(session, key_expr, decode, **kwargs)


async def aquery_one(
    session: zenoh.Session,
    key_expr: str,
    request: msgspec.Struct | bytes | None,
    reply_type: type[M],
    *,
    timeout_s: float = DEFAULT_TIMEOUT_S,
) -> M:
    """:func:`query_one` without blocking the event loop."""
    replies = await aquery(session, key_expr, request, reply_type, timeout_s=timeout_s)
    return _first(replies, key_expr)


# --- serving ------------------------------------------------------------------------------------

ErrorReply = Callable[[ErrorInfo], msgspec.Struct]
"""Builds the reply message for an error, e.g. ``lambda e: SubmitReply(ok=False, error=e)``."""


def _send_error(query: zenoh.Query, key: str, info: ErrorInfo, on_error: ErrorReply | None) -> None:
    if on_error is not None:
        query.reply(key, encode(on_error(info)), encoding=JSON)
    else:
        query.reply_err(encode(info), encoding=JSON)


def _send_error_and_drop(
    query: zenoh.Query, key: str, info: ErrorInfo, on_error: ErrorReply | None
) -> None:
    try:
        _send_error(query, key, info, on_error)
    except Exception as exc:  # e.g. the querier is gone, or the session closed
        log.warning("could not send error reply on %s: %s", key, exc)
    finally:
        query.drop()  # type: ignore[no-untyped-call]


def _internal(key: str, exc: Exception) -> ErrorInfo:
    log.error("handler of %s failed", key, exc_info=exc)
    return ErrorInfo(code="internal", message=f"internal error: {str(exc) or type(exc).__name__}")


def _reply(
    query: zenoh.Query, key: str, reply: msgspec.Struct, on_error: ErrorReply | None
) -> None:
    try:
        payload = encode(reply)
    except Exception as exc:  # a reply that cannot be encoded still gets an answer
        _send_error_and_drop(query, key, _internal(key, exc), on_error)
        return
    try:
        query.reply(key, payload, encoding=JSON)
    except Exception as exc:  # e.g. the querier is gone, or the session closed
        log.warning("could not reply on %s: %s", key, exc)
    finally:
        query.drop()  # type: ignore[no-untyped-call]


def _decode_request(query: zenoh.Query, request_type: type[Any] | None) -> Any:
    """The request of a query; raises :class:`MessageError` only (whatever the payload).

    ``request_type=None``: the key takes no request; no payload, ``{}`` or ``{"v": 1}`` only.
    A payload over :func:`~bus.codec.request_limit` is refused before it is copied out of Zenoh.
    """
    limit = request_limit(request_type)
    try:
        payload = query.payload
        if payload is not None:
            check_size(len(payload), limit)
        raw = payload.to_bytes() if payload is not None else b""
        if request_type is None:
            if raw.strip():
                decode(raw, Request, max_bytes=limit)
            return None
        return decode(raw, request_type, max_bytes=limit)
    except MessageError:
        raise
    except Exception as exc:
        info = ErrorInfo(code="bad_json", message=f"unreadable request: {type(exc).__name__}")
        raise MessageError(info) from None


@overload
def serve(
    session: zenoh.Session,
    key: str,
    request_type: type[M],
    handler: Callable[[M], msgspec.Struct],
    *,
    on_error: ErrorReply | None = None,
) -> zenoh.Queryable[None]: ...
@overload
def serve(
    session: zenoh.Session,
    key: str,
    request_type: None,
    handler: Callable[[None], msgspec.Struct],
    *,
    on_error: ErrorReply | None = None,
) -> zenoh.Queryable[None]: ...
def serve(
    session: zenoh.Session,
    key: str,
    request_type: type[Any] | None,
    handler: Callable[[Any], msgspec.Struct],
    *,
    on_error: ErrorReply | None = None,
) -> zenoh.Queryable[None]:
    """Answer queries on ``key`` with ``handler(request)`` run on Zenoh's thread.

    ``request_type=None``: the key takes no request (e.g. snapshots); ``handler(None)`` runs for
    a query without payload, ``{}`` or ``{"v": 1}``, anything else gets an error reply.
    """

    def callback(query: zenoh.Query) -> None:
        try:
            request = _decode_request(query, request_type)
        except MessageError as exc:
            _send_error_and_drop(query, key, exc.info, on_error)
            return
        try:
            reply = handler(request)
        except Exception as exc:
            _send_error_and_drop(query, key, _internal(key, exc), on_error)
            return
        _reply(query, key, reply, on_error)

    return session.declare_queryable(key, callback, complete=True)


@overload
def serve_async(
    session: zenoh.Session,
    key: str,
    request_type: type[M],
    handler: Callable[[M], Awaitable[msgspec.Struct]],
    *,
    loop: asyncio.AbstractEventLoop | None = None,
    on_error: ErrorReply | None = None,
) -> zenoh.Queryable[None]: ...
@overload
def serve_async(
    session: zenoh.Session,
    key: str,
    request_type: None,
    handler: Callable[[None], Awaitable[msgspec.Struct]],
    *,
    loop: asyncio.AbstractEventLoop | None = None,
    on_error: ErrorReply | None = None,
) -> zenoh.Queryable[None]: ...
def serve_async(
    session: zenoh.Session,
    key: str,
    request_type: type[Any] | None,
    handler: Callable[[Any], Awaitable[msgspec.Struct]],
    *,
    loop: asyncio.AbstractEventLoop | None = None,
    on_error: ErrorReply | None = None,
) -> zenoh.Queryable[None]:
    """Like :func:`serve`, but ``handler`` is a coroutine run in ``loop`` (default: running loop).

    Requests are decoded on Zenoh's thread; valid ones are scheduled on the loop in arrival order.
    """
    return serve_async_keyed(
        session, key, request_type, lambda _asked, request: handler(request), loop=loop,
        on_error=on_error, reply_on_asked=False,
    )  # fmt: skip


def serve_async_keyed(
    session: zenoh.Session,
    key: str,
    request_type: type[Any] | None,
    handler: Callable[[str, Any], Awaitable[msgspec.Struct]],
    *,
    loop: asyncio.AbstractEventLoop | None = None,
    on_error: ErrorReply | None = None,
    reply_on_asked: bool = True,
) -> zenoh.Queryable[None]:
    """Like :func:`serve_async`, but ``key`` is a wildcard whose literal key says who asks
    (``orchestrator/submit/<identity>``: access control lets each identity query only its own):
    ``handler(asked_key, request)``, and the reply goes out on the key asked (the handler refuses
    a wildcard one itself)."""
    import asyncio

    target_loop = loop or asyncio.get_running_loop()

    async def run(query: zenoh.Query, asked: str, request: Any) -> None:
        try:
            reply = await handler(asked, request)
        except Exception as exc:
            _send_error_and_drop(query, asked, _internal(asked, exc), on_error)
            return
        _reply(query, asked, reply, on_error)

    def callback(query: zenoh.Query) -> None:
        asked = str(query.key_expr) if reply_on_asked else key
        try:
            request = _decode_request(query, request_type)
        except MessageError as exc:
            _send_error_and_drop(query, asked, exc.info, on_error)
            return
        try:
            asyncio.run_coroutine_threadsafe(run(query, asked, request), target_loop)
        except RuntimeError:  # loop closed: the service is stopping
            info = ErrorInfo(code="unavailable", message="service stopping")
            _send_error_and_drop(query, asked, info, on_error)

    return session.declare_queryable(key, callback, complete=True)

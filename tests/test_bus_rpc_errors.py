"""bus.rpc over real loopback Zenoh: every malformed request gets exactly one error reply.

Whatever the bytes (too deep, not UTF-8, NaN, huge numbers, overlong strings, wrong types), on a
thread queryable and an asyncio one, with and without an error-reply builder; a reply that cannot
be encoded becomes ``internal``; a key that takes no request refuses a payload. Error codes never
leak a class name.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable, Iterator
from typing import Any

import msgspec
import pytest

from bus.codec import encode
from bus.keys import ShowKeys
from bus.messages import CommandReply, ErrorInfo, OperatorCommand, ShowSnapshot
from bus.rpc import (
    ErrorReply,
    NoReplyError,
    RemoteError,
    aquery_one,
    error_info_from_exception,
    query,
    query_one,
    serve,
    serve_async,
)
from bus.session import BusSettings, Session, loopback_settings, open_session
from planner.errors import InfeasibleTrajectoryError, PlannerError

KEYS = ShowKeys("rpc-errors")
WAIT_S = 10.0  # bound for declarations to propagate on loopback; never a timing assertion

MALFORMED: list[tuple[bytes, str]] = [
    (b"", "bad_json"),
    (b"{oops", "bad_json"),
    (b"[" * 100_000, "too_deep"),
    (b'{"command": "cancel", "job_id": ' + b"[" * 1000 + b"]" * 1000 + b"}", "too_deep"),
    (b'{"command": "cancel", "job_id": "\xff\xfe"}', "bad_json"),
    (b'{"command": "prioritize", "job_id": "j", "priority": NaN}', "bad_json"),
    (b'{"command": "prioritize", "job_id": "j", "priority": Infinity}', "bad_json"),
    (b'{"command": "prioritize", "job_id": "j", "priority": 1' + b"0" * 400 + b"}", "invalid"),
    (b'{"command": "prioritize", "job_id": "j", "priority": 1e308}', "invalid"),
    (b'{"command": "cancel", "job_id": "' + b"j" * 200_000 + b'"}', "invalid"),
    (b'{"command": "cancel", "job_id": 5}', "invalid"),
    (b'{"command": "cancel", "colour": "red"}', "invalid"),
    (b'{"command": "self_destruct"}', "invalid"),
    (b'{"command": "cancel"} trailing', "bad_json"),
    (b'"just a string"', "invalid"),
    (b"\x00\x01\x02\xff", "bad_json"),
    (b'{"command": "pause", "reason": "' + b"x" * 1_100_000 + b'"}', "too_large"),
]


@pytest.fixture(scope="module")
def settings() -> BusSettings:
    return loopback_settings()


@pytest.fixture(scope="module")
def clients(settings: BusSettings) -> Iterator[tuple[Session, Session]]:
    with (
        open_session(settings, role="router"),
        open_session(settings, role="client") as a,
        open_session(settings, role="client") as b,
    ):
        yield a, b


def _served(session: Session, key: str) -> None:
    deadline = time.monotonic() + WAIT_S
    while not query(session, key, None, CommandReply, timeout_s=0.5):
        assert time.monotonic() < deadline, f"nobody serves {key}"


def _codes(session: Session, key: str) -> list[list[tuple[bool, str | None]]]:
    """Per malformed payload: each reply as (came as a CommandReply ok=false, error code)."""
    out = []
    for payload, _ in MALFORMED:
        got = []
        for reply in query(session, key, payload, CommandReply, timeout_s=5.0):
            error = reply.value.error if reply.value is not None else reply.error
            as_reply = reply.value is not None and not reply.value.ok
            got.append((as_reply, error.code if error is not None else None))
        out.append(got)
    return out


def _handle(cmd: OperatorCommand) -> CommandReply:
    return CommandReply(ok=True, message=cmd.command)


def _reply_error(info: ErrorInfo) -> CommandReply:
    return CommandReply(ok=False, message=info.message, error=info)


@pytest.mark.parametrize("on_error", [None, _reply_error], ids=["zenoh_error", "reply_type"])
def test_thread_queryable_answers_every_malformed_request_once(
    clients: tuple[Session, Session], on_error: ErrorReply | None
) -> None:
    a, b = clients
    q = serve(b, KEYS.command, OperatorCommand, _handle, on_error=on_error)
    try:
        _served(a, KEYS.command)
        got = _codes(a, KEYS.command)
        assert query(a, KEYS.command, OperatorCommand(command="pause"), CommandReply)[0].value
    finally:
        q.undeclare()  # type: ignore[no-untyped-call]
    expected = [[(on_error is not None, code)] for _, code in MALFORMED]
    assert got == expected


@pytest.mark.parametrize("on_error", [None, _reply_error], ids=["zenoh_error", "reply_type"])
def test_async_queryable_answers_every_malformed_request_once(
    clients: tuple[Session, Session], on_error: ErrorReply | None
) -> None:
    a, b = clients

    async def handle(cmd: OperatorCommand) -> CommandReply:
        return _handle(cmd)

    async def main() -> list[list[tuple[bool, str | None]]]:
        q = serve_async(b, KEYS.command, OperatorCommand, handle, on_error=on_error)
        try:
            await asyncio.to_thread(_served, a, KEYS.command)
            return await asyncio.to_thread(_codes, a, KEYS.command)
        finally:
            q.undeclare()  # type: ignore[no-untyped-call]

    got = asyncio.run(main())
    assert got == [[(on_error is not None, code)] for _, code in MALFORMED]


def test_a_key_without_request_refuses_payloads(clients: tuple[Session, Session]) -> None:
    a, b = clients
    snapshot = ShowSnapshot(show_id="s", time_s=0.0, queue_paused=False, jobs=[], vehicles=[])
    q = serve(b, KEYS.snapshot, None, lambda _: snapshot)
    try:
        deadline = time.monotonic() + WAIT_S
        while not query(a, KEYS.snapshot, None, ShowSnapshot, timeout_s=0.5):
            assert time.monotonic() < deadline
        for ok in (None, b"", b"{}", b'{"v": 1}', b"  "):
            (reply,) = query(a, KEYS.snapshot, ok, ShowSnapshot)
            assert reply.value == snapshot, ok
        for bad, code in (
            (b'{"x": 1}', "invalid"),
            (b"[" * 5000, "too_deep"),
            (b"\xff", "bad_json"),
        ):
            (reply,) = query(a, KEYS.snapshot, bad, ShowSnapshot)
            assert reply.error is not None and reply.error.code == code, bad
    finally:
        q.undeclare()  # type: ignore[no-untyped-call]


def test_a_reply_that_cannot_be_encoded_is_an_internal_error(
    clients: tuple[Session, Session],
) -> None:
    a, b = clients
    broken: Callable[[OperatorCommand], Any] = lambda cmd: CommandReply(  # noqa: E731
        ok=True,
        message=object(),  # type: ignore[arg-type]
    )
    q = serve(b, KEYS.command, OperatorCommand, broken, on_error=_reply_error)
    try:
        _served(a, KEYS.command)
        (reply,) = query(a, KEYS.command, OperatorCommand(command="pause"), CommandReply)
        assert reply.value is not None and not reply.value.ok
        assert reply.value.error is not None and reply.value.error.code == "internal"
    finally:
        q.undeclare()  # type: ignore[no-untyped-call]


@pytest.mark.parametrize("ask", ["thread", "asyncio"])
def test_an_error_reply_that_is_no_errorinfo_is_no_answer(
    clients: tuple[Session, Session], ask: str
) -> None:
    """Zenoh's own error reply (a router's "Timeout", no ErrorInfo in it) is not the service's
    answer: the caller hears no reply, as for silence, while the service's own ErrorInfo stays a
    refusal. Taken as an answer, it let an agent's ``done`` go unstored and a character was
    written twice."""
    a, b = clients
    refusal = encode(ErrorInfo(code="busy", message="b"))
    payloads = {KEYS.command: b"Timeout", KEYS.snapshot: refusal}

    def answer(query: Any) -> None:
        query.reply_err(payloads[str(query.key_expr)])
        query.drop()

    queryables = [b.declare_queryable(key, answer, complete=True) for key in payloads]
    try:
        _served(a, KEYS.command)
        ask_one = query_one if ask == "thread" else lambda *a: asyncio.run(aquery_one(*a))
        with pytest.raises(NoReplyError, match="only: Timeout"):
            ask_one(a, KEYS.command, None, CommandReply)
        with pytest.raises(RemoteError, match="busy"):
            ask_one(a, KEYS.snapshot, None, CommandReply)
    finally:
        for q in queryables:
            q.undeclare()


class _CodedError(Exception):
    def __init__(self, code: object) -> None:
        super().__init__("x")
        self.code = code


def test_error_codes_are_stable_snake_case_never_class_names() -> None:
    planner = error_info_from_exception(PlannerError("bad", stroke_index=2, point_index=3))
    assert (planner.code, planner.stroke_index, planner.point_index) == ("plan_failed", 2, 3)
    limit = InfeasibleTrajectoryError("fast", limit="v_max", axis=None, t_s=1, value=2, bound=1)
    assert error_info_from_exception(limit).code == "plan_failed"
    assert error_info_from_exception(ValueError("v")).code == "internal"
    assert error_info_from_exception(_CodedError("takeoff_refused")).code == "takeoff_refused"
    for odd in ("PlannerError", "has space", "", 5, None, "x" * 80):
        assert error_info_from_exception(_CodedError(odd)).code == "internal", odd
    assert (
        error_info_from_exception(_CodedError(1), default_code="plan_failed").code == "plan_failed"
    )
    assert msgspec.json.decode(msgspec.json.encode(planner), type=ErrorInfo) == planner

"""bus.session / bus.pubsub / bus.rpc on real loopback Zenoh sessions (router + 2 clients)."""

from __future__ import annotations

import asyncio
import gc
import json
import threading
import time
from collections.abc import Callable, Iterator
from typing import TypeVar

import msgspec
import pytest

from bus.bridge import FifoChannel
from bus.keys import ShowKeys
from bus.messages import (
    CommandReply,
    ErrorInfo,
    Event,
    OperatorCommand,
    ShowSnapshot,
    SubmitReply,
    SubmitRequest,
)
from bus.pubsub import (
    MessagePublisher,
    alive_keys,
    declare_token,
    publish,
    subscribe,
    subscribe_raw,
    watch_liveliness,
)
from bus.rpc import (
    NoReplyError,
    RemoteError,
    aquery_one,
    query,
    query_one,
    serve,
    serve_async,
)
from bus.session import (
    BusSettings,
    Session,
    SessionOpenError,
    build_config,
    free_tcp_endpoint,
    loopback_settings,
    open_session,
)

T = TypeVar("T")
KEYS = ShowKeys("bus-test")
WAIT_S = 5.0  # upper bound for delivery on loopback; never a timing assertion


@pytest.fixture(scope="module")
def settings() -> BusSettings:
    return loopback_settings()


@pytest.fixture(scope="module")
def router(settings: BusSettings) -> Iterator[Session]:
    with open_session(settings, role="router") as session:
        yield session


@pytest.fixture()
def clients(router: Session, settings: BusSettings) -> Iterator[tuple[Session, Session]]:
    with (
        open_session(settings, role="client") as a,
        open_session(settings, role="client") as b,
    ):
        yield a, b


def _eventually(fn: Callable[[], T]) -> T:
    """fn() once it is truthy (Zenoh propagates declarations asynchronously), bounded."""
    deadline = time.monotonic() + WAIT_S
    while not (value := fn()) and time.monotonic() < deadline:
        time.sleep(0.02)
    return value


def _wait_served(session: Session, key: str) -> None:
    """Wait until a queryable on ``key`` is reachable (declarations propagate asynchronously)."""
    assert _eventually(lambda: query(session, key, None, CommandReply, timeout_s=0.5))


def _event(message: str) -> Event:
    return Event(time_s=1.0, level="info", kind="test", message=message)


def _get(conf: object, key: str) -> object:
    return json.loads(conf.get_json(key))  # type: ignore[attr-defined]


def test_config_is_explicit_and_passes_tls_and_acl_through() -> None:
    tls = {"root_ca_certificate": "/etc/ca.pem", "enable_mtls": True}
    acl = {"enabled": True, "default_permission": "deny", "rules": []}
    settings = BusSettings(
        router_listen=["tcp/127.0.0.1:7447"],
        connect=["tcp/10.0.0.1:7447"],
        tls=tls,
        access_control=acl,
        extra={"transport/unicast/max_sessions": 77},
    )
    client = build_config(settings, role="client")
    assert _get(client, "mode") == "client"
    assert _get(client, "connect/endpoints") == ["tcp/10.0.0.1:7447"]
    assert _get(client, "listen/endpoints") == []
    assert _get(client, "scouting/multicast/enabled") is False
    assert _get(client, "transport/link/tls/root_ca_certificate") == "/etc/ca.pem"
    assert _get(client, "transport/link/tls/enable_mtls") is True
    assert _get(client, "access_control/default_permission") == "deny"
    assert _get(client, "transport/unicast/max_sessions") == 77
    router = build_config(settings, role="router")
    assert _get(router, "listen/endpoints") == ["tcp/127.0.0.1:7447"]
    assert _get(router, "connect/endpoints") == []  # a router does not dial its own clients


def test_client_without_router_fails_after_the_deadline() -> None:
    settings = BusSettings(router_listen=[], connect=[free_tcp_endpoint()])
    with pytest.raises(SessionOpenError, match="client"):
        open_session(settings, role="client", open_timeout_s=0.2)


def test_pub_sub_round_trip(clients: tuple[Session, Session]) -> None:
    a, b = clients
    got: list[tuple[str, Event]] = []
    bad: list[str] = []
    done = threading.Event()

    def on_message(key: str, msg: Event) -> None:
        got.append((key, msg))
        if len(got) == 2:
            done.set()

    sub = subscribe(b, KEYS.events, Event, on_message, on_error=lambda k, e: bad.append(k))
    probe = threading.Event()
    raw = subscribe_raw(b, f"{KEYS.prefix}/**", lambda s: probe.set())
    for _ in range(100):  # subscriptions propagate through the router asynchronously
        publish(a, f"{KEYS.prefix}/probe", _event("probe"))
        if probe.wait(0.05):
            break
    a.put(KEYS.events, b"{not json")
    publish(a, KEYS.events, _event("first"))
    pub = MessagePublisher(a, KEYS.events)
    pub.put(_event("second"))
    assert done.wait(WAIT_S)
    assert [m.message for _, m in got] == ["first", "second"]
    assert {k for k, _ in got} == {KEYS.events}
    assert bad == [KEYS.events]
    pub.undeclare()
    sub.undeclare()
    raw.undeclare()


def _handle_command(cmd: OperatorCommand) -> CommandReply:
    if cmd.command == "estop":
        raise RuntimeError("boom")
    return CommandReply(ok=True, message=f"did {cmd.command} {cmd.job_id}")


def test_query_reply_and_errors_never_kill_the_queryable(clients: tuple[Session, Session]) -> None:
    a, b = clients
    q = serve(b, KEYS.command, OperatorCommand, _handle_command)
    _wait_served(a, KEYS.command)
    reply = query_one(a, KEYS.command, OperatorCommand(command="cancel", job_id="j1"), CommandReply)
    assert reply.ok and reply.message == "did cancel j1"
    # bad JSON -> ErrorInfo error reply
    with pytest.raises(RemoteError) as bad_json:
        query_one(a, KEYS.command, b"{oops", CommandReply)
    assert bad_json.value.info.code == "bad_json"
    # unknown field -> names the field
    replies = query(a, KEYS.command, b'{"command": "pause", "colour": 3}', CommandReply)
    assert len(replies) == 1 and replies[0].error is not None
    assert replies[0].error.code == "invalid"
    # wrong type -> names the field
    with pytest.raises(RemoteError) as wrong:
        query_one(a, KEYS.command, b'{"command": "cancel", "job_id": 5}', CommandReply)
    assert wrong.value.info.field == "$.job_id"
    # handler exception -> internal error, and the queryable still answers
    with pytest.raises(RemoteError) as internal:
        query_one(a, KEYS.command, OperatorCommand(command="estop"), CommandReply)
    assert internal.value.info.code == "internal"
    assert query_one(a, KEYS.command, OperatorCommand(command="pause"), CommandReply).ok
    q.undeclare()
    with pytest.raises(NoReplyError):
        query_one(a, KEYS.command, OperatorCommand(command="pause"), CommandReply, timeout_s=0.3)


def test_error_reply_builder_answers_in_the_reply_type(clients: tuple[Session, Session]) -> None:
    a, b = clients

    def on_submit(req: SubmitRequest) -> SubmitReply:
        return SubmitReply(ok=True, job_id="j-" + (req.text or ""))

    q = serve(
        b, KEYS.submit, SubmitRequest, on_submit, on_error=lambda e: SubmitReply(ok=False, error=e)
    )
    _wait_served(a, KEYS.submit)
    huge = b'{"text": "' + b"x" * 1_100_000 + b'"}'
    reply = query_one(a, KEYS.submit, huge, SubmitReply)
    assert not reply.ok and reply.error is not None and reply.error.code == "too_large"
    assert query_one(a, KEYS.submit, SubmitRequest(text="L"), SubmitReply).job_id == "j-L"
    q.undeclare()


def test_liveliness_appears_and_disappears(clients: tuple[Session, Session]) -> None:
    a, b = clients
    changes: list[tuple[str, bool]] = []
    appeared, gone = threading.Event(), threading.Event()

    def on_change(key: str, alive: bool) -> None:
        changes.append((key, alive))
        (appeared if alive else gone).set()

    watcher = watch_liveliness(a, KEYS.vehicles_alive_all, on_change)
    token = declare_token(b, KEYS.vehicle_alive("uav1"))
    assert appeared.wait(WAIT_S)
    assert _eventually(lambda: alive_keys(a, KEYS.vehicles_alive_all)) == {
        KEYS.vehicle_alive("uav1")
    }
    token.undeclare()
    assert gone.wait(WAIT_S)
    assert changes == [(KEYS.vehicle_alive("uav1"), True), (KEYS.vehicle_alive("uav1"), False)]
    watcher.undeclare()


def test_liveliness_of_a_closed_session_disappears(router: Session, settings: BusSettings) -> None:
    appeared, gone = threading.Event(), threading.Event()
    with open_session(settings, role="client") as watcher_session:
        watch_liveliness(
            watcher_session,
            KEYS.vehicles_alive_all,
            lambda k, alive: (appeared if alive else gone).set(),
        )
        with open_session(settings, role="peer") as vehicle:
            declare_token(vehicle, KEYS.vehicle_alive("uav9"))  # result dropped on purpose
            gc.collect()
            assert appeared.wait(WAIT_S)
            assert not gone.wait(0.3)  # still declared although nobody holds the token
        assert gone.wait(WAIT_S)  # the session closed without undeclaring: still reported gone


def test_late_joiner_gets_state_from_a_queryable(router: Session, settings: BusSettings) -> None:
    state = ShowSnapshot(show_id="bus-test", time_s=3.0, queue_paused=True, jobs=[], vehicles=[])
    with open_session(settings, role="client") as service:
        serve(service, KEYS.snapshot, None, lambda _: state)
        _wait_served(service, KEYS.snapshot)
        # the late joiner opens its session only now, after the state was set
        with open_session(settings, role="client") as late:
            got = query_one(late, KEYS.snapshot, None, ShowSnapshot)
    assert got == state


def test_async_queryable_and_query_keep_order(clients: tuple[Session, Session]) -> None:
    a, b = clients

    async def main() -> list[str]:
        seen: FifoChannel[str] = FifoChannel()

        async def handle(cmd: OperatorCommand) -> CommandReply:
            seen.push(cmd.job_id or "")
            await asyncio.sleep(0)
            return CommandReply(ok=True, message=cmd.job_id or "")

        q = serve_async(b, KEYS.command, OperatorCommand, handle)
        await asyncio.to_thread(_wait_served, a, KEYS.command)
        replies = await asyncio.gather(
            *(
                aquery_one(
                    a, KEYS.command, OperatorCommand(command="cancel", job_id=f"j{i}"), CommandReply
                )
                for i in range(20)
            )
        )
        q.undeclare()
        assert [r.message for r in replies] == [f"j{i}" for i in range(20)]
        return seen.drain()

    handled = asyncio.run(main())
    assert sorted(handled) == sorted(f"j{i}" for i in range(20))


def test_messages_encode_to_plain_json() -> None:
    raw = msgspec.json.encode(ErrorInfo(code="x", message="y"))
    assert msgspec.json.decode(raw) == {
        "v": 1,
        "code": "x",
        "message": "y",
        "field": None,
        "stroke_index": None,
        "point_index": None,
        "reason": None,
    }

"""Async queries over real loopback Zenoh: replies, errors and silence reach the caller, many at
once, without a Python thread started per query (one poller per event loop collects them)."""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Iterator
from typing import Any

import pytest
import zenoh

from bus.codec import encode
from bus.messages import CommandReply, ErrorInfo
from bus.rpc import NoReplyError, RemoteError, aquery, aquery_one
from bus.session import Session, loopback_settings, open_session

KEY = "reply-poll/echo"
FAILING = "reply-poll/failing"


def _echo(query: zenoh.Query) -> None:
    """Replies with the request's bytes as the message (on Zenoh's own thread: no Python thread)."""
    text = query.payload.to_bytes().decode() if query.payload is not None else ""
    query.reply(KEY, encode(CommandReply(ok=True, message=text)))


def _fail(query: zenoh.Query) -> None:
    query.reply_err(encode(ErrorInfo(code="busy", message="not now")))


@pytest.fixture(scope="module")
def session() -> Iterator[Session]:
    settings = loopback_settings()
    with open_session(settings, role="router") as server:
        server.declare_queryable(KEY, zenoh.handlers.Callback(_echo, indirect=False))
        server.declare_queryable(FAILING, zenoh.handlers.Callback(_fail, indirect=False))
        with open_session(settings, role="client") as client:
            yield client


def test_many_async_queries_get_their_own_replies_and_start_no_thread(
    session: Session, monkeypatch: pytest.MonkeyPatch
) -> None:
    asyncio.run(aquery_one(session, KEY, b"warm-up", CommandReply, timeout_s=10.0))
    started: list[str] = []
    start = threading.Thread.start

    def counting_start(thread: threading.Thread) -> None:
        started.append(thread.name)
        start(thread)

    monkeypatch.setattr(threading.Thread, "start", counting_start)

    async def main() -> list[Any]:
        asks = [aquery_one(session, KEY, str(i).encode(), CommandReply) for i in range(40)]
        return await asyncio.gather(*asks)

    replies = asyncio.run(main())
    assert [reply.message for reply in replies] == [str(i) for i in range(40)]
    assert started == []  # Zenoh's indirect callbacks started one per query


def test_an_error_reply_and_silence_end_the_query(session: Session) -> None:
    async def main() -> tuple[list[Any], BaseException]:
        failed = await aquery(session, FAILING, None, CommandReply, timeout_s=10.0)
        with pytest.raises(RemoteError) as remote:
            await aquery_one(session, FAILING, None, CommandReply, timeout_s=10.0)
        with pytest.raises(NoReplyError):
            await aquery_one(session, "reply-poll/nobody", None, CommandReply, timeout_s=0.2)
        return failed, remote.value

    failed, remote = asyncio.run(main())
    assert len(failed) == 1 and failed[0].error is not None
    assert failed[0].error.code == "busy"
    assert isinstance(remote, RemoteError) and remote.info.message == "not now"


def test_a_cancelled_query_leaves_the_others_answered(session: Session) -> None:
    async def main() -> list[str]:
        dropped = asyncio.create_task(aquery_one(session, KEY, b"dropped", CommandReply))
        kept = [aquery_one(session, KEY, str(i).encode(), CommandReply) for i in range(3)]
        await asyncio.sleep(0)
        dropped.cancel()
        return [reply.message for reply in await asyncio.gather(*kept)]

    assert asyncio.run(main()) == ["0", "1", "2"]

"""Quotas on the bus, per identity (issue 30): one submitter cannot block the public.

The pure rules first (:mod:`orchestrator.quotas`, the Book's caps), then the flood of the issue
over a real secured bus: the show's own CA and certificates, the router in this process with the
generated access control, the orchestrator in a thread.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from test_orchestrator_service import RunningOrchestrator, make_show

from bus.keys import ShowKeys
from bus.messages import ShowSnapshot, SubmitReply, SubmitRequest
from bus.rpc import query, query_one
from bus.session import Session, free_tcp_endpoint, open_session
from cli.main import main as skyquill
from kiosk.jobs import JobBook
from kiosk.link import OrchestratorLink
from orchestrator.core import Book, CoreConfig
from orchestrator.quotas import QuotaPolicy, SubmitQuotas
from showfile import SecuritySettings, Show
from trust.settings import client_session_settings, session_settings

FLOOD = 200


def test_a_client_gets_its_quota_a_minute_then_rate_limited_with_when_to_retry() -> None:
    quotas = SubmitQuotas(QuotaPolicy(client_per_minute=3, kiosk_per_minute=5))
    assert [quotas.refusal("submitter@booth", 0, t) for t in (0.0, 1.0, 2.0)] == [None] * 3
    refused = quotas.refusal("submitter@booth", 0, 30.0)
    assert refused is not None and refused.code == "rate_limited"
    assert refused.message == "submitter@booth may submit 3 a minute: try again in 30 s"
    assert quotas.refusal("submitter@other", 0, 30.0) is None  # each identity its own
    assert quotas.refusal("submitter@booth", 0, 60.5) is None  # the first left the window
    assert all(quotas.refusal("kiosk", 0, 1.0) is None for _ in range(5))
    assert quotas.refusal("kiosk", 0, 1.0) is not None
    assert all(quotas.refusal(op, 0, 1.0) is None for op in ["operator", "operator@al"] * 50)


def test_a_client_may_have_only_so_many_jobs_waiting() -> None:
    quotas = SubmitQuotas(QuotaPolicy(client_per_minute=100, client_max_waiting=2))
    refused = quotas.refusal("submitter@booth", 2, 0.0)
    assert (
        refused is not None
        and refused.code == "rate_limited"
        and "2 jobs waiting" in refused.message
    )
    assert quotas.refusal("submitter@booth", 1, 0.0) is None
    assert quotas.refusal("kiosk", 500, 0.0) is None  # the kiosk's visitors: the global caps


def test_jobs_awaiting_approval_are_capped_apart_from_the_queue() -> None:
    book = Book(
        CoreConfig(show_id="s", vehicles=(), moderation=True, max_queue=1, max_awaiting=2),
        now_s=0.0,
    )
    for n in range(3):
        reply, _ = book.submit(
            f"j{n}",
            SubmitRequest(text="L"),
            label="L",
            estimate_s=1.0,
            now_s=0.0,
            submitted_by="kiosk",
        )
        assert reply.ok == (n < 2), reply
    assert reply.error is not None and reply.error.code == "queue_full"
    assert reply.error.message == "the queue is full (2 jobs awaiting approval)"
    mine, _ = book.submit(
        "j9", SubmitRequest(text="L"), label="L", estimate_s=1.0, now_s=0.0, submitted_by="operator"
    )
    assert mine.ok  # the operator's own are never refused
    assert book.waiting_of("kiosk") == 2 and book.waiting_of("operator") == 1


@pytest.fixture
def secured_show(tmp_path: Path) -> Iterator[Show]:
    """A moderated show on a free loopback port with its keys, a submitter client issued with
    ``skyquill keys --client``, and its router running in this process."""
    path, show = make_show(
        tmp_path,
        "quotas",
        free_tcp_endpoint(),
        policy={"moderation": True},
        security=SecuritySettings(mode="mtls", keys_dir=tmp_path / "keys"),
    )
    assert skyquill(["keys", str(path), "--client", "booth", "--role", "submitter"]) == 0
    with open_session(session_settings(show, "router"), role="router"):
        yield show


def _as(show: Show, identity: str) -> Session:
    return open_session(session_settings(show, identity), role="client", open_timeout_s=10.0)


def _answering(session: Session, keys: ShowKeys) -> Session:
    """``session`` once the orchestrator answers on it (it declares its queryables after it
    says it is ready)."""
    deadline = time.monotonic() + 10.0
    while not query(session, keys.snapshot, None, ShowSnapshot, timeout_s=1.0):
        assert time.monotonic() < deadline, "the orchestrator does not answer"
        time.sleep(0.05)
    return session


@pytest.mark.timeout(120)
def test_a_flood_from_one_submitter_leaves_the_kiosk_and_the_operator_their_turn(
    secured_show: Show, capsys: pytest.CaptureFixture[str]
) -> None:
    show, keys = secured_show, ShowKeys(secured_show.show_id)
    folder = show.keys_dir / "clients" / "booth"
    own_key = keys.submit_as("submitter@booth")
    with (
        RunningOrchestrator(show),
        open_session(client_session_settings(show, folder), role="client") as flooder,
        _as(show, "kiosk") as kiosk_session,
        _as(show, "operator") as console,
    ):
        _answering(console, keys)
        started_s = time.monotonic()
        replies = [
            query_one(flooder, own_key, SubmitRequest(text="X", client_id=f"c{n}"), SubmitReply)
            for n in range(FLOOD)  # a new client_id each time: the key, not the claim, counts
        ]
        flood_s = time.monotonic() - started_s
        accepted = [r for r in replies if r.ok]
        refused = [r.error for r in replies if not r.ok and r.error is not None]
        assert len(accepted) == show.policy.client_submits_per_minute
        assert len(refused) == FLOOD - len(accepted)
        assert {e.code for e in refused} == {"rate_limited"}
        assert "submitter@booth may submit 6 a minute: try again in" in refused[0].message
        for other in (keys.submit, keys.submit_as("kiosk"), keys.submits_all):
            assert query(flooder, other, SubmitRequest(text="X"), SubmitReply, timeout_s=1.0) == []
        after_s = time.monotonic()
        link = OrchestratorLink(kiosk_session, keys, JobBook())
        visitor = asyncio.run(link.submit(SubmitRequest(text="A", client_id="kiosk-visitor")))
        mine = query_one(
            console, keys.submit, SubmitRequest(text="B", client_id="cli"), SubmitReply
        )
        turn_s = time.monotonic() - after_s
    assert visitor.ok and visitor.state == "awaiting_approval", visitor
    assert mine.ok and mine.state == "awaiting_approval", mine
    assert turn_s < 1.0
    with capsys.disabled():
        print(
            f"\nflood of {FLOOD} from one submitter: {len(accepted)} accepted, {len(refused)} "
            f"rate_limited in {flood_s:.2f} s; then kiosk + operator accepted in {turn_s:.3f} s"
        )


@pytest.mark.timeout(60)
def test_without_security_the_key_names_a_claimed_identity_and_a_wildcard_is_forbidden(
    tmp_path: Path,
) -> None:
    """``security: none``: no access rules, so the identity in the key is only a claim (any
    client may take any name); a key that names nobody is refused by the orchestrator."""
    _, show = make_show(tmp_path, "claims", free_tcp_endpoint())
    keys = ShowKeys(show.show_id)
    with (
        open_session(session_settings(show, "router"), role="router"),
        RunningOrchestrator(show),
        _as(show, "operator") as anyone,
    ):
        _answering(anyone, keys)
        claimed = query_one(anyone, keys.submit_as("kiosk"), SubmitRequest(text="A"), SubmitReply)
        wildcard = query_one(anyone, keys.submits_all, SubmitRequest(text="A"), SubmitReply)
    assert claimed.ok, claimed
    assert not wildcard.ok and wildcard.error is not None and wildcard.error.code == "forbidden"

"""Payload limits over real loopback Zenoh (issue 30: bounded memory under hostile sizes).

A submission over ``bus.codec.MAX_REQUEST_BYTES`` gets one one-line ``too_large`` reply and its
handler never runs, while the kiosk's largest drawing is served; an assignment carrying the
largest submission's strokes is served although it is a little larger; a message over
``bus.session.MAX_MESSAGE_BYTES`` is dropped by the router (the queryable never sees it, the
link lives on); a reply as large as a full show's snapshot still arrives.
"""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import pytest
import zenoh

from bus.codec import MAX_PAYLOAD_BYTES, MAX_REQUEST_BYTES, encode
from bus.keys import ShowKeys
from bus.messages import (
    CommandReply,
    JobAssignment,
    JobState,
    ShowSnapshot,
    SubmitReply,
    SubmitRequest,
    VehicleCommand,
)
from bus.rpc import query, query_one, serve
from bus.session import MAX_MESSAGE_BYTES, Session, loopback_settings, open_session

KEYS = ShowKeys("limits")
WAIT_S = 10.0  # bound for declarations to propagate on loopback; never a timing assertion
RAW_KEY = f"{KEYS.prefix}/raw"


def kiosk_drawing(points: int, strokes: int = 60) -> dict[str, Any]:
    """A drawing as the kiosk's pad sends it with widths: ``{"x", "y", "t", "w"}`` points,
    4-digit coordinates (a large screen), times in [s] to the millisecond, widths in [m]."""
    sizes = [points // strokes + (k < points % strokes) for k in range(strokes)]
    starts = [sum(sizes[:k]) for k in range(strokes)]
    drawn = [
        [
            {"x": 1000.5 + i % 900, "y": 100.5 + i % 800, "t": round(i / 60, 3), "w": 0.01234}
            for i in range(start, start + n)
        ]
        for start, n in zip(starts, sizes, strict=True)
    ]
    canvas = {"width": 1920, "height": 1080}
    return {"units": "px", "y_axis": "down", "canvas": canvas, "strokes": drawn}


def padded(doc: dict[str, Any], size_bytes: int) -> SubmitRequest:
    """A submission of ``doc`` made exactly ``size_bytes`` long by an ignored field."""
    bare = len(encode(SubmitRequest(strokes={**doc, "pad": ""}, client_id="k")))
    assert bare <= size_bytes
    return SubmitRequest(strokes={**doc, "pad": "x" * (size_bytes - bare)}, client_id="k")


@dataclass
class Served:
    """What the handlers and the raw queryable saw."""

    submissions: list[int] = field(default_factory=list)
    """Encoded size of each submission a handler got."""
    assignments: list[str] = field(default_factory=list)
    raw_queries: list[int] = field(default_factory=list)
    lock: threading.Lock = field(default_factory=threading.Lock)


def _submit(served: Served, request: SubmitRequest) -> SubmitReply:
    with served.lock:
        served.submissions.append(len(encode(request)))
    return SubmitReply(ok=True, job_id="j1")


def _assign(served: Served, command: VehicleCommand) -> CommandReply:
    assert command.job is not None
    with served.lock:
        served.assignments.append(command.job.job_id)
    return CommandReply(ok=True)


def _snapshot() -> ShowSnapshot:
    """About 900 kB: what the orchestrator's snapshot may reach in a 250-vehicle show."""
    jobs = [
        JobState(
            job_id=f"j{k:012x}",
            state="done",
            label="drawing (60 strokes)",
            kind="strokes",
            client_id="k" * 100,
            created_at_s=1.7e9 + k * 0.123456,
            updated_at_s=1.7e9 + k * 0.223456,
            strokes={"note": "s" * 2_000},
        )
        for k in range(360)
    ]
    return ShowSnapshot(show_id="limits", time_s=1.7e9, queue_paused=False, jobs=jobs, vehicles=[])


@pytest.fixture(scope="module")
def bus() -> Iterator[tuple[Session, Served]]:
    served = Served()
    settings = loopback_settings()
    with (
        open_session(settings, role="router"),
        open_session(settings, role="client") as server,
        open_session(settings, role="client") as client,
    ):

        def count_raw(query: zenoh.Query) -> None:
            payload = query.payload
            with served.lock:
                served.raw_queries.append(len(payload) if payload is not None else 0)
            query.reply(RAW_KEY, b"{}")

        declared = [
            serve(
                server,
                KEYS.submit,
                SubmitRequest,
                lambda request: _submit(served, request),
                on_error=lambda e: SubmitReply(ok=False, error=e),
            ),
            serve(
                server,
                KEYS.vehicle_assign("v1"),
                VehicleCommand,
                lambda command: _assign(served, command),
                on_error=lambda e: CommandReply(ok=False, message=e.message, error=e),
            ),
            serve(server, KEYS.snapshot, None, lambda _: _snapshot()),
            server.declare_queryable(RAW_KEY, count_raw, complete=True),
        ]
        deadline = time.monotonic() + WAIT_S
        while not query(client, RAW_KEY, None, ShowSnapshot, timeout_s=0.5):
            assert time.monotonic() < deadline, "the queryables were never declared"
        yield client, served
        for queryable in declared:
            queryable.undeclare()  # type: ignore[no-untyped-call]


@pytest.mark.parametrize("size_bytes", [300_000, 999_000])
def test_a_submission_over_the_request_limit_gets_one_too_large_reply(
    bus: tuple[Session, Served], size_bytes: int
) -> None:
    client, served = bus
    request = padded(kiosk_drawing(2000), size_bytes)
    before = list(served.submissions)
    replies = query(client, KEYS.submit, request, SubmitReply, timeout_s=5.0)
    assert len(replies) == 1 and replies[0].value is not None
    error = replies[0].value.error
    assert not replies[0].value.ok and error is not None
    assert error.code == "too_large"
    assert error.message == f"payload of {size_bytes} bytes exceeds {MAX_REQUEST_BYTES} bytes"
    assert served.submissions == before  # the handler never ran


def test_the_kiosk_s_largest_drawing_is_served(bus: tuple[Session, Served]) -> None:
    client, served = bus
    request = SubmitRequest(strokes=kiosk_drawing(5000), client_id="kiosk")
    reply = query_one(client, KEYS.submit, request, SubmitReply, timeout_s=5.0)
    assert reply.ok and len(encode(request)) in served.submissions


def test_an_assignment_of_the_largest_submission_is_served(bus: tuple[Session, Served]) -> None:
    client, served = bus
    largest = padded(kiosk_drawing(5000), MAX_REQUEST_BYTES)
    assert query_one(client, KEYS.submit, largest, SubmitReply, timeout_s=5.0).ok
    job = JobAssignment(job_id="j-largest", strokes=largest.strokes)
    command = VehicleCommand(command="assign", job=job)
    assert len(encode(command)) > MAX_REQUEST_BYTES  # re-encoded with the job's fields
    reply = query_one(client, KEYS.vehicle_assign("v1"), command, CommandReply, timeout_s=5.0)
    assert reply.ok and "j-largest" in served.assignments


def test_a_message_over_the_zenoh_bound_is_dropped_by_the_router(
    bus: tuple[Session, Served],
) -> None:
    client, served = bus
    before = list(served.raw_queries)
    huge = json.dumps({"text": "x" * MAX_MESSAGE_BYTES}).encode()
    query(client, RAW_KEY, huge, ShowSnapshot, timeout_s=2.0)
    assert served.raw_queries == before  # nobody past the router held it
    assert query(client, RAW_KEY, None, ShowSnapshot, timeout_s=5.0)  # the link lives on
    assert served.raw_queries[-1] == 0


def test_a_reply_as_large_as_a_full_snapshot_arrives(bus: tuple[Session, Served]) -> None:
    client, _ = bus
    size = len(encode(_snapshot()))
    assert MAX_REQUEST_BYTES < 0.8 * MAX_PAYLOAD_BYTES < size <= MAX_PAYLOAD_BYTES
    snapshot = query_one(client, KEYS.snapshot, None, ShowSnapshot, timeout_s=5.0)
    assert len(snapshot.jobs) == 360

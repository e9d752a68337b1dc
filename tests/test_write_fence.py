"""The write fence (``bus/fence.py``): no character is written by two vehicles, under any
interleaving of delays, restarts and losses.

A property over random schedules: the agent's real lease (``vehicle_agent/lease.py``) decides
tick by tick whether its vehicle may still ink; the orchestrator's real ``Book`` (restarted from
what it stored, or not) decides when another vehicle may be given the job. The last instant the
old holder inks must come before the first instant anyone else may have it. Both run on one time
line here (the agent's monotonic clock and the orchestrator's Unix clock differ by a constant,
and only durations are compared).
"""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from bus.messages import AgentReport, SubmitRequest, VehicleStatus
from orchestrator.core import Book, CoreConfig
from orchestrator.fleet import EtaModel, VehicleInfo
from orchestrator.holders import writing_fence_s
from vehicle_agent.lease import JobLease

LOST_AFTER_S = 1.5
TICK_S = 0.01
VEHICLES = (
    VehicleInfo("uav1", "quadrotor-brush", "b1"),
    VehicleInfo("uav2", "quadrotor-brush", "b2"),
)


def _config(time_scale: float) -> CoreConfig:
    return CoreConfig(
        show_id="t",
        vehicles=VEHICLES,
        lost_after_s=LOST_AFTER_S,
        eta=EtaModel(time_scale=time_scale),
    )


def _status(vid: str, job_id: str | None) -> VehicleStatus:
    state = "writing" if job_id else "idle"
    return VehicleStatus(vehicle_id=vid, kind="quadrotor-brush", state=state, job_id=job_id)  # type: ignore[arg-type]


def _last_ink_s(lease: JobLease, begin_s: float, writing_wall_s: float) -> float:
    """When the vehicle stops inking: the end of its writing, or its lease's first breach."""
    t = begin_s
    end = begin_s + writing_wall_s
    while t < end:
        if lease.breach(0.0, t) is not None:
            return t
        t += TICK_S
    return end


@settings(max_examples=300, deadline=None)
@given(
    planned_s=st.floats(2.0, 120.0),
    time_scale=st.sampled_from([1.0, 2.0, 4.0, 6.0]),
    slowdown=st.floats(1.0, 3.0),
    delay_to_orch_s=st.floats(0.0, 1.0),
    ack_back=st.booleans(),
    delay_back_s=st.floats(0.0, 1.0),
    outage_after_s=st.floats(0.0, 30.0),
    restart=st.booleans(),
)
def test_the_old_holder_never_inks_once_another_vehicle_may_have_the_job(
    planned_s: float,
    time_scale: float,
    slowdown: float,
    delay_to_orch_s: float,
    ack_back: bool,
    delay_back_s: float,
    outage_after_s: float,
    restart: bool,
) -> None:
    """``started`` is sent at 10 s, reaches the orchestrator after ``delay_to_orch_s``; its
    acknowledgement reaches the agent after ``delay_back_s`` (or never). After
    ``outage_after_s`` nothing more is heard either way (the router, the orchestrator or the
    link died); the orchestrator is restarted from its store or goes on, loses the vehicle, and
    holds the job. The writing takes ``slowdown`` times its plan (a loaded host)."""
    config = _config(time_scale)
    book = Book(config, now_s=0.0)
    book.liveliness("uav1", True, 0.0)
    book.status(_status("uav1", None), 0.0)
    reply, _ = book.submit("j1", SubmitRequest(text="L"), label="L", estimate_s=9.0, now_s=1.0)
    assert reply.ok and book.jobs["j1"].vehicle_id == "uav1"

    lease = JobLease(LOST_AFTER_S, time_scale=time_scale)
    lease.hold("j1", active=True, writing=False, now_s=1.0)
    lease.acknowledged("j1", 9.5)  # a holding report just before writing
    sent_s = 10.0
    assert lease.may_begin_writing(sent_s)
    lease.hold("j1", active=True, writing=True, now_s=sent_s)
    received_s = sent_s + delay_to_orch_s
    started = AgentReport(
        vehicle_id="uav1", job_id="j1", event="started", planned_duration_s=planned_s
    )
    book.status(_status("uav1", "j1"), received_s)
    assert book.report(started, received_s)[0].ok
    if ack_back:
        lease.acknowledged("j1", sent_s, planned_s)
    outage_s = received_s + outage_after_s
    # confirmations keep coming until the outage (progress reports every 0.5 s)
    t = sent_s
    while t + 0.5 < outage_s and ack_back:
        t += 0.5
        book.status(_status("uav1", "j1"), t)
        book.report(AgentReport(vehicle_id="uav1", job_id="j1", event="progress"), t)
        lease.acknowledged("j1", t - delay_back_s)
    last_ink_s = _last_ink_s(lease, sent_s, slowdown * planned_s / time_scale)

    if restart:
        book = Book(config, list(book.jobs.values()), now_s=outage_s + 0.5)
    else:
        book.liveliness("uav1", False, outage_s)
    book.liveliness("uav2", True, outage_s + 0.5)
    book.status(_status("uav2", None), outage_s + 0.5)
    first_free_s = math.inf
    t = outage_s + 0.5
    while t < last_ink_s + 60.0:
        book.tick(t)
        job = book.jobs["j1"]
        if job.state != "queued" or job.holder_hold_until_s is None:
            if job.vehicle_id == "uav2" or job.state == "queued":
                first_free_s = t
                break
        elif t >= job.holder_hold_until_s:
            first_free_s = t
            break
        t += 0.25
    assert last_ink_s < first_free_s, (last_ink_s, first_free_s)


def test_the_fence_is_the_planned_writing_with_room_after_the_start() -> None:
    config = _config(time_scale=2.0)
    book = Book(config, now_s=0.0)
    book.liveliness("uav1", True, 0.0)
    book.status(_status("uav1", None), 0.0)
    book.submit("j1", SubmitRequest(text="L"), label="L", estimate_s=9.0, now_s=1.0)
    rep = AgentReport(vehicle_id="uav1", job_id="j1", event="started", planned_duration_s=20.0)
    book.report(rep, 10.0)
    fence = writing_fence_s(config, book.jobs["j1"])
    assert fence == 10.0 + LOST_AFTER_S + 1.5 * 20.0 / 2.0  # 10 s of wall writing, +50 %
    lease = JobLease(LOST_AFTER_S, time_scale=2.0)
    lease.hold("j1", active=True, writing=True, now_s=9.9)
    lease.acknowledged("j1", 9.9, 20.0)
    assert lease.breach(0.0, 9.9 + 16.4) is None and lease.breach(0.0, 9.9 + 16.6) is not None
    unacknowledged = JobLease(LOST_AFTER_S, time_scale=2.0)
    unacknowledged.hold("j1", active=True, writing=True, now_s=9.9)
    assert unacknowledged.breach(0.0, 9.9 + 1.6) is not None  # lost_after_s only

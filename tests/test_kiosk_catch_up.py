"""A visitor's page is not left on ``writing`` for good when the job's final message is lost:
the 1 Hz ``fleet`` snapshot lists no finished job, so a followed job that is unfinished at the
kiosk and missing there is asked of the orchestrator's ``snapshot`` (kiosk/link.py). Real Zenoh
on loopback: a router, the orchestrator's side played by a test session, the kiosk's link."""

from __future__ import annotations

import asyncio
import time

from bus.keys import ShowKeys
from bus.messages import JobState, ShowSnapshot
from bus.pubsub import publish
from bus.rpc import serve
from bus.session import Session, loopback_settings, open_session
from kiosk.jobs import JobBook
from kiosk.link import OrchestratorLink

KEYS = ShowKeys("kiosk-catch-up")
JOB_ID = "j1"


def _state(state: str, at_s: float) -> JobState:
    return JobState(
        job_id=JOB_ID,
        state=state,  # type: ignore[arg-type]
        label="永",
        kind="text",
        client_id="kiosk",
        created_at_s=at_s,
        updated_at_s=at_s,
        vehicle_id="uav1",
    )


async def _follow(orchestrator: Session, kiosk: Session, *, listed: bool) -> tuple[str, int]:
    """The job's state at the kiosk after the orchestrator's final message went unsent and
    three ``fleet`` snapshots came (listing the job still writing when ``listed``), and how many
    times the kiosk asked for the show's snapshot."""
    now_s = time.time()
    asked: list[float] = []

    def snapshot(_request: None) -> ShowSnapshot:
        asked.append(time.time())
        jobs = [_state("done", now_s + 1.0)]
        return ShowSnapshot(show_id="s", time_s=now_s, queue_paused=False, jobs=jobs, vehicles=[])

    queryable = serve(orchestrator, KEYS.snapshot, None, snapshot)
    link = OrchestratorLink(kiosk, KEYS, JobBook(), timeout_s=2.0)
    await link.start()
    ticket = link.book.add(session_id="visitor", label="永", preview=None)
    link.book.bind(ticket.ticket, JOB_ID)
    try:
        with link.watch(ticket.ticket):
            deadline = time.monotonic() + 10.0
            while link.book.state(JOB_ID) is None:  # the subscriptions reach the router
                assert time.monotonic() < deadline, "the job's state never arrived"
                publish(orchestrator, KEYS.job(JOB_ID), _state("writing", now_s))
                await asyncio.sleep(0.05)
            # the "done" message on jobs/j1 is lost; the fleet snapshots go on
            fleet_jobs = [_state("writing", now_s)] if listed else []
            fleet = ShowSnapshot(
                show_id="s", time_s=now_s, queue_paused=False, jobs=fleet_jobs, vehicles=[]
            )
            for _ in range(3):
                publish(orchestrator, KEYS.fleet, fleet)
                await asyncio.sleep(0.5)
            state = link.book.state(JOB_ID)
            assert state is not None
            return state.state, len(asked)
    finally:
        await link.close()
        queryable.undeclare()  # type: ignore[no-untyped-call]


def _run(*, listed: bool) -> tuple[str, int]:
    settings = loopback_settings()
    with (
        open_session(settings, role="router"),
        open_session(settings, role="client") as orchestrator,
        open_session(settings, role="client") as kiosk,
    ):
        return asyncio.run(_follow(orchestrator, kiosk, listed=listed))


def test_a_followed_job_gone_from_the_fleet_snapshot_is_asked_for_and_ends_done() -> None:
    state, asked = _run(listed=False)
    assert state == "done" and asked >= 1


def test_a_job_still_listed_is_not_asked_for() -> None:
    assert _run(listed=True) == ("writing", 0)


def test_a_kiosk_just_started_is_not_stale_until_it_missed_a_snapshot() -> None:
    """Staleness counts from the link's start until the first ``fleet`` snapshot: a kiosk just
    started has missed nothing, and its first visitors were told the show was slow."""
    now = [100.0]
    link = OrchestratorLink(None, KEYS, JobBook(), clock=lambda: now[0])  # type: ignore[arg-type]
    assert not link.stale(2.0)
    now[0] += 2.5  # no snapshot in 2.5 s: the orchestrator or the bus is down
    assert link.stale(2.0)
    link.fleet_seen_s = now[0]
    now[0] += 1.0
    assert not link.stale(2.0)
    now[0] += 1.5
    assert link.stale(2.0)

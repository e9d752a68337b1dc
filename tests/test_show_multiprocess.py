"""A whole show as separate processes over real Zenoh on loopback: orchestrator + four agents.

One show runs for the whole module (router in this process, children supervised as in
``skyquill up``), on a free port with its own storage, sped up by ``time_scale``. Each test submits
its own characters; the last one also checks every submission acknowledged during the module.
"""

from __future__ import annotations

import os
import signal
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from bus.messages import Event, JobState
from bus.pubsub import subscribe
from bus.session import Session
from cli.showrun import ShowRun, Stagehand, derived_show, snapshot, submit_texts, wait_for_jobs
from showfile import load_show

pytestmark = [pytest.mark.multiprocess, pytest.mark.slow, pytest.mark.timeout(240)]

AIRSHOW = Path(__file__).resolve().parent.parent / "shows" / "airshow-2014.yaml"
TIME_SCALE = 6.0
LOST_AFTER_S = 1.0
JOB_TIMEOUT_S = 90.0


@dataclass
class LiveShow:
    run: ShowRun
    session: Session
    events: list[Event] = field(default_factory=list)
    acknowledged: list[str] = field(default_factory=list)
    lock: threading.Lock = field(default_factory=threading.Lock)
    said: list[str] = field(default_factory=list)

    def submit(self, texts: list[str]) -> list[str]:
        replies = submit_texts(self.session, self.run.keys, texts)
        ids = [str(reply.job_id) for reply in replies]
        assert all(reply.ok and reply.job_id for reply in replies)
        self.acknowledged.extend(ids)
        return ids

    def wait(self, job_ids: list[str]) -> list[JobState]:
        return wait_for_jobs(self.session, self.run.keys, job_ids, timeout_s=JOB_TIMEOUT_S)

    def job(self, job_id: str) -> JobState | None:
        jobs = {j.job_id: j for j in snapshot(self.session, self.run.keys).jobs}
        return jobs.get(job_id)

    def wait_until_writing(self, job_ids: list[str]) -> JobState:
        """One of ``job_ids`` with its writing begun and under half done: one caught later may
        be finished, its report on its way, before the test's fault strikes (and rightly count
        as written once)."""
        deadline = time.monotonic() + JOB_TIMEOUT_S
        while time.monotonic() < deadline:
            for job_id in job_ids:
                job = self.job(job_id)
                if job is not None and job.state == "writing" and 0.0 < job.progress < 0.5:
                    return job
            time.sleep(0.1)
        raise AssertionError(f"none of {job_ids} started writing")

    def events_of(self, kind: str) -> list[Event]:
        with self.lock:
            return [e for e in self.events if e.kind == kind]


@pytest.fixture(scope="module")
def live(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LiveShow]:
    out = tmp_path_factory.mktemp("show")
    base = load_show(AIRSHOW)
    path, show = derived_show(
        AIRSHOW,
        out,
        time_scale=TIME_SCALE,
        policy=base.policy.model_copy(update={"lost_after_s": LOST_AFTER_S}),
        controller=base.controller.model_copy(update={"preset": "default"}),
    )
    said: list[str] = []
    with ShowRun(path, show, log_dir=out / "logs", say=said.append) as run, run.client() as session:
        live = LiveShow(run, session, said=said)

        def on_event(_key: str, event: Event) -> None:
            with live.lock:
                live.events.append(event)

        subscriber = subscribe(session, run.keys.events, Event, on_event)
        with Stagehand(session, run.keys):  # fresh sheets on boards left half-written
            yield live
        subscriber.undeclare()  # type: ignore[no-untyped-call]


def test_eight_characters_are_all_written_with_metrics(live: LiveShow) -> None:
    texts = ["一", "L", "二", "十", "I", "T", "V", "Z"]
    jobs = live.wait(live.submit(texts))
    assert [j.state for j in jobs] == ["done"] * 8, [(j.label, j.state, j.error) for j in jobs]
    assert {j.vehicle_id for j in jobs} == {"uav1", "uav2", "uav3", "uav4"}
    for job in jobs:
        m = job.metrics
        assert m is not None, job
        assert 0.0 < m.rmse_pen_down_m < 0.02, (job.label, m)
        assert m.max_error_m < 0.05 and m.duration_s > 1.0, (job.label, m)
        assert m.iou is not None and m.iou > 0.5, (job.label, m)


def test_an_agent_killed_mid_character_is_detected_and_another_vehicle_finishes(
    live: LiveShow,
) -> None:
    (job_id,) = live.submit(["L"])
    writing = live.wait_until_writing([job_id])
    victim = writing.vehicle_id
    assert victim is not None
    pid = live.run.supervisor.pid(f"agent {victim}")
    assert pid is not None
    killed_at = time.time()
    os.kill(pid, signal.SIGKILL)
    (job,) = live.wait([job_id])
    assert job.state == "done" and job.vehicle_id not in (None, victim)
    assert job.attempts >= 2 and job.metrics is not None  # more if an assignment went unanswered
    # Detected: lost within 2 s (silent past lost_after_s 1.5); or, when the supervisor's restart
    # brings the vehicle back sooner than that (0.5 s plus its start), back without its job,
    # which the orchestrator takes from it after confirm_grace_s (3 s) of not hearing it named.
    lost, requeued = (
        [e for e in live.events_of(kind) if e.vehicle_id == victim and e.time_s >= killed_at]
        for kind in ("vehicle_lost", "job_requeued")
    )
    if lost:
        assert lost[0].time_s - killed_at < 2.0
    else:
        assert requeued, "the killed agent was not detected"
        assert requeued[0].time_s - killed_at < 2.0 + 3.0 + 1.0  # back, grace, a tick's slack
    deadline = time.monotonic() + 30.0
    while live.run.supervisor.restarts(f"agent {victim}") < 1:  # and `up` brings it back
        assert time.monotonic() < deadline
        time.sleep(0.1)
    assert any(line.startswith(f"agent {victim} exited (killed by SIGKILL)") for line in live.said)


def test_the_orchestrator_killed_and_restarted_loses_no_acknowledged_submission(
    live: LiveShow,
) -> None:
    job_ids = live.submit(["一", "L", "十", "I"])
    interrupted = live.wait_until_writing(job_ids)
    pid = live.run.supervisor.pid("orchestrator")
    assert pid is not None
    os.kill(pid, signal.SIGKILL)
    deadline = time.monotonic() + 30.0
    while live.run.supervisor.pid("orchestrator") in (None, pid):
        assert time.monotonic() < deadline, "the orchestrator was not restarted"
        time.sleep(0.1)
    jobs = live.wait(list(live.acknowledged))
    assert [j.state for j in jobs] == ["done"] * len(jobs), [(j.job_id, j.state) for j in jobs]
    assert all(j.metrics is not None for j in jobs)
    again = next(j for j in jobs if j.job_id == interrupted.job_id)
    # written on through the restart by the vehicle that had it (the write fence, bus/fence.py)
    assert (again.attempts, again.vehicle_id) == (1, interrupted.vehicle_id), again
    assert any(line.startswith("orchestrator exited (killed by SIGKILL)") for line in live.said)

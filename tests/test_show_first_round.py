"""No cold start in a running show (issue 35): a vehicle's first job reaches its writing as soon
as its next ones do, so the queue's ETAs, which give every job the same approach
(``orchestrator/fleet.py:EtaModel.before_write_s``), carry no offset for the first round.

Before, the agent's planning worker was started by the first job: its imports (1.0-1.4 s CPU,
19.5 s wall at load 25) came on top of that job's approach, and every ETA of a 16-job queue was
early by the same 29-35 s (``benchmarks/bench_show.py --eta-only``).
"""

from __future__ import annotations

import statistics
import threading
import time
from pathlib import Path

import pytest

from bus.messages import JobState
from bus.pubsub import subscribe
from bus.rpc import NoReplyError, RemoteError
from bus.session import Session
from cli.showrun import ShowRun, Stagehand, derived_show, snapshot, submit_texts, wait_for_jobs

pytestmark = [pytest.mark.multiprocess, pytest.mark.slow, pytest.mark.timeout(240)]

SOLO = Path(__file__).resolve().parent.parent / "shows" / "solo.yaml"
TIME_SCALE = 4.0
"""The approach (take-off, transit, settle: about 11 s of show time) is 2.7 s of wall time; a
cold worker adds at least 1.2 s of CPU to the first one."""


class FirstSeen:
    """When each job was first published in each state (orchestrator time [s])."""

    def __init__(self) -> None:
        self.at_s: dict[tuple[str, str], float] = {}
        self._lock = threading.Lock()

    def on_job(self, _key: str, job: JobState) -> None:
        with self._lock:
            self.at_s.setdefault((job.job_id, job.state), job.updated_at_s)

    def approach_s(self, job_id: str) -> float:
        """Wall time in [s] from the job's assignment to its writing."""
        with self._lock:
            return self.at_s[(job_id, "writing")] - self.at_s[(job_id, "assigned")]


def wait_idle(run: ShowRun, session: Session, timeout_s: float = 120.0) -> None:
    """Until the show's vehicle reports itself idle (its agent joined the show)."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            vehicles = snapshot(session, run.keys, timeout_s=2.0).vehicles
        except (NoReplyError, RemoteError):  # the orchestrator is starting
            vehicles = []
        if any(v.alive and v.state in ("idle", "landed") for v in vehicles):
            return
        time.sleep(0.3)
    raise AssertionError(f"no vehicle idle after {timeout_s:.0f} s")


def test_a_vehicles_first_job_starts_writing_as_soon_as_its_next_ones(tmp_path: Path) -> None:
    path, show = derived_show(SOLO, tmp_path, time_scale=TIME_SCALE)
    seen = FirstSeen()
    with (
        ShowRun(path, show, log_dir=tmp_path / "logs") as run,
        run.client() as session,
        Stagehand(session, run.keys),
    ):
        _sub = subscribe(session, run.keys.jobs_all, JobState, seen.on_job)
        wait_idle(run, session)
        ids = [str(r.job_id) for r in submit_texts(session, run.keys, ["二", "三", "十"])]
        jobs = wait_for_jobs(session, run.keys, ids, timeout_s=150.0)
        time.sleep(0.3)  # the last publications
    assert [j.state for j in jobs] == ["done"] * 3, [(j.label, j.state, j.error) for j in jobs]
    first, *later = (seen.approach_s(job_id) for job_id in ids)
    assert first <= 1.25 * statistics.median(later) + 0.5, (first, later)

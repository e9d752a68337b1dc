"""A phrase written together by separate processes over real Zenoh: orchestrator + four agents.

uav3 takes off 5 m further from its board than the others, so its approach takes seconds
longer: the four vehicles begin inking within a bound of each other only because each holds at
the start of its writing until the orchestrator acknowledges its *ready* report, which it does
once every character of the phrase has reported ready (``orchestrator/phrases.py``).
"""

from __future__ import annotations

import threading
import time
from pathlib import Path

import pytest

from bus.messages import SubmitReply, SubmitRequest, Telemetry
from bus.pubsub import subscribe
from bus.rpc import NoReplyError, query_one
from bus.session import Session
from cli.showrun import ShowRun, Stagehand, derived_show, snapshot, wait_for_jobs
from showfile import load_show

pytestmark = [pytest.mark.multiprocess, pytest.mark.slow, pytest.mark.timeout(240)]

AIRSHOW = Path(__file__).resolve().parent.parent / "shows" / "airshow-2014.yaml"
TIME_SCALE = 3.0
LOST_AFTER_S = 1.5
START_BOUND_S = 1.0
"""Wall [s] between the first and the last vehicle's brush going down: one ready period
(``lost_after_s / 3``), a report's round trip and a telemetry period, with room for a busy host."""
FAR_Y_M = -6.2
"""uav3's home y in [m], 5 m further from the boards than the others' (-1.2 m)."""


def test_a_phrase_is_written_by_four_vehicles_that_start_together(
    tmp_path: Path,
) -> None:
    base = load_show(AIRSHOW)
    far = tuple(
        v.model_copy(update={"home_m_enu": (v.home_m_enu[0], FAR_Y_M, 0.0)})
        if v.id == "uav3"
        else v
        for v in base.vehicles
    )
    path, show = derived_show(
        AIRSHOW,
        tmp_path,
        time_scale=TIME_SCALE,
        vehicles=far,
        policy=base.policy.model_copy(update={"lost_after_s": LOST_AFTER_S}),
    )
    pen_down_at: dict[str, float] = {}
    lock = threading.Lock()

    def on_telemetry(_key: str, sample: Telemetry) -> None:
        if sample.pen_down and sample.job_id is not None:
            with lock:
                pen_down_at.setdefault(sample.job_id, time.monotonic())

    with ShowRun(path, show, log_dir=tmp_path / "logs") as run, run.client() as session:
        subscriber = subscribe(session, run.keys.telemetry_all, Telemetry, on_telemetry)
        with Stagehand(session, run.keys):
            request = SubmitRequest(text="新年快乐", phrase=True, client_id="test")
            reply = _submit(session, run.keys.submit, request)
            job_ids = _phrase_jobs(session, run, reply.job_id)
            assert len(job_ids) == 4 and job_ids[0] == reply.job_id
            jobs = wait_for_jobs(session, run.keys, job_ids, timeout_s=150.0)
        subscriber.undeclare()  # type: ignore[no-untyped-call]
    assert [j.state for j in jobs] == ["done"] * 4, [(j.label, j.state, j.error) for j in jobs]
    assert [j.label for j in jobs] == list("新年快乐")
    assert [j.vehicle_id for j in jobs] == ["uav1", "uav2", "uav3", "uav4"]  # reading order
    starts = [pen_down_at[j.job_id] for j in jobs]
    assert max(starts) - min(starts) <= START_BOUND_S, starts


def _submit(session: Session, key: str, request: SubmitRequest) -> SubmitReply:
    """Submit, retrying while the orchestrator is not answering yet."""
    deadline = time.monotonic() + 30.0
    while True:
        try:
            reply = query_one(session, key, request, SubmitReply, timeout_s=5.0)
        except NoReplyError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.5)
            continue
        assert reply.ok and reply.job_id, reply
        return reply


def _phrase_jobs(session: Session, run: ShowRun, phrase_id: str | None) -> list[str]:
    """The phrase's job ids in reading order, from the orchestrator's snapshot."""
    jobs = snapshot(session, run.keys).jobs
    mine = [j for j in jobs if j.phrase is not None and j.phrase.phrase_id == phrase_id]
    return [j.job_id for j in sorted(mine, key=lambda j: j.phrase.index if j.phrase else 0)]

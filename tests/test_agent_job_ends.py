"""Every job that ends has a report (issue 34): a job stopped by an operator's cancel or land, an
emergency stop, a vehicle fault or its lease is scored, kept and pictured as an aborted one.

The flights are closed loops (the agent's job runner and the in-process sim of the solo show's
brush quadrotor, ``tests/live_kinds.py``), the jobs planned, measured and recorded by the
functions ``skyquill agent``'s worker runs, through the agent's own end of a job
(``vehicle_agent/job_end.py``). Before, these jobs kept their files but sent no report, and their
picture title said ``broken off (cancelled)`` whatever the end.
"""

from __future__ import annotations

import asyncio
import json
import pickle
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import pytest
from job_traces import SHOWS
from live_kinds import LiveRun

from bus.keys import ShowKeys
from bus.messages import AgentReport, CommandReply, ErrorInfo, JobAssignment, VehicleCommand
from showfile import load_show
from vehicle_agent import reports
from vehicle_agent.backends.base import VehicleSnapshot
from vehicle_agent.events import EventOutbox
from vehicle_agent.job_end import job_result, measured_and_kept
from vehicle_agent.job_guard import JobGuard
from vehicle_agent.job_picture import ORDER_NAME, PictureOrder, PictureWorker, write_order
from vehicle_agent.jobs import archive_job, job_metrics, prepare_job
from vehicle_agent.lease import JobLease
from vehicle_agent.reports import ReportOutbox
from vehicle_agent.runner_io import AbortedJob, TickActions
from vehicle_agent.work import ThreadJobWork

pytestmark = pytest.mark.timeout(300)

WRITTEN_BEFORE_END = 0.4
"""The fraction of its plan the vehicle has written when the job is ended."""


class OrdersOnly(PictureWorker):
    """Writes the picture order into the job's directory and draws nothing (the drawing is
    ``tests/test_agent_job_picture.py``'s)."""

    def submit(self, job_dir: Path, order: PictureOrder) -> None:
        write_order(job_dir, order)


def _solo(tmp_path: Path) -> LiveRun:
    """uav1 of the solo show, its job files in ``tmp_path``."""
    show = load_show(SHOWS / "solo.yaml")
    storage = show.storage.model_copy(
        update={"database": tmp_path / "show.sqlite3", "job_files": "compact"}
    )
    return LiveRun(show.model_copy(update={"storage": storage}), "uav1")


def _recording(run: LiveRun) -> list[TickActions]:
    """Every tick's actions of ``run`` from now on."""
    seen: list[TickActions] = []
    step = run.runner.step

    def recorded(snapshot: VehicleSnapshot, now_s: float) -> TickActions:
        seen.append(step(snapshot, now_s))
        return seen[-1]

    run.runner.step = recorded  # type: ignore[method-assign]
    return seen


def _fly_until(run: LiveRun, done: Callable[[LiveRun], bool]) -> None:
    assert run.assign(JobAssignment(job_id="j1", text="一", attempt=1))
    while not done(run):
        run.tick()
        assert run.now_s < 120.0, run.phases


def _writing_from(fraction: float) -> Callable[[LiveRun], bool]:
    def done(run: LiveRun) -> bool:
        job = run.runner._job
        return run.runner.phase == "write" and job is not None and job.progress >= fraction

    return done


def _faulty(run: LiveRun) -> None:
    """The sim vehicle reports a fault from its next snapshot on (as a backend's does)."""
    snapshot = run.vehicle.snapshot
    run.vehicle.snapshot = lambda: replace(snapshot(), fault="motor 3 lost")  # type: ignore[method-assign]


def _end(run: LiveRun, kind: str) -> None:
    """End the running job as ``kind`` does in the agent."""
    runner, now_s = run.runner, run.now_s
    if kind == "cancel":
        runner.handle_command(VehicleCommand(command="cancel", job_id="j1"), now_s)
    elif kind in ("land", "estop"):
        runner.handle_command(VehicleCommand(command=kind), now_s)  # type: ignore[arg-type]
    elif kind == "fault":
        _faulty(run)
    else:  # the service's guard, as when the lease ran out or the orchestrator said not_assigned
        guard = JobGuard(JobLease(lost_after_s=3.0), runner, EventOutbox("uav1"), "uav1")
        guard.give_up("not acknowledged for 3.2 s")


def _ended(run: LiveRun, kind: str) -> AbortedJob:
    """The job's end as the runner hands it to the service."""
    seen = _recording(run)
    _end(run, kind)
    run.tick()
    aborted = [a.aborted for a in seen if a.aborted is not None]
    assert len(aborted) == 1, kind
    return aborted[0]


def _finish(run: LiveRun, aborted: AbortedJob) -> tuple[AgentReport, Path]:
    """What the agent's service does with it (``AgentService._finish``)."""
    setup, prepared = run.setup, run.prepared["j1"]
    work = ThreadJobWork(
        lambda assignment: prepare_job(setup, assignment),
        lambda prepared, trace: job_metrics(setup, prepared, trace),
        lambda prepared, trace, metrics: archive_job(
            setup, OrdersOnly("uav1"), prepared, trace, metrics
        ),
    )
    trace = aborted.trace
    metrics = asyncio.run(measured_and_kept(work, prepared, trace, "uav1"))
    bounds = setup.runner_config.safety.writing
    report = job_result("uav1", prepared, trace, metrics, bounds, aborted)
    folder = setup.show.database_path.parent / "jobs" / "j1-uav1-1"
    return report, folder


ENDS = {
    "cancel": ("cancelled", "cancelled at 4"),
    "land": ("landed_by_operator", "landed on the operator's command at 4"),
    "estop": ("estop", "stopped by an emergency stop at 4"),
    "fault": ("vehicle_fault", "ended by a vehicle fault at 4"),
    "lease": ("given_up", "given up on its lease at 4"),
}
"""Each end: the reason its trace, metrics and report carry, and how its sentence begins (at
40-49% of its plan)."""


@pytest.mark.parametrize("kind", sorted(ENDS))
def test_a_job_ended_while_writing_is_scored_pictured_and_reported(
    kind: str, tmp_path: Path
) -> None:
    reason, sentence = ENDS[kind]
    run = _solo(tmp_path)
    _fly_until(run, _writing_from(WRITTEN_BEFORE_END))
    aborted = _ended(run, kind)
    assert aborted.report is None  # no result of its own: the orchestrator decides, as before
    report, folder = _finish(run, aborted)

    summary = json.loads((folder / "metrics.json").read_text(encoding="utf-8"))
    assert summary["abort_reason"] == reason
    assert summary["ended"].startswith(sentence) and summary["ended"].endswith("of its plan")
    fraction = summary["metrics"]["flown_fraction"]
    assert fraction == pytest.approx(WRITTEN_BEFORE_END, abs=0.02)
    assert summary["metrics"]["rmse_pen_down_m"] is not None  # the pen came down: measured
    assert 0.0 < summary["metrics"]["iou"] < 0.9  # scored against the whole character
    order = pickle.loads((folder / ORDER_NAME).read_bytes())
    assert isinstance(order, PictureOrder) and f", {summary['ended']}" in order.title

    assert report.event == "ended" and report.error is not None
    assert report.error.code == reason and report.error.message == summary["ended"]
    assert report.metrics is not None and report.metrics.flown_fraction == fraction
    assert report.progress == fraction and report.retry_after_s is None


def test_a_job_cancelled_before_its_pen_came_down_says_so_and_scores_nothing(
    tmp_path: Path,
) -> None:
    run = _solo(tmp_path)
    _fly_until(run, lambda run: run.runner.phase == "write")  # its first tick of writing
    report, folder = _finish(run, _ended(run, "cancel"))
    summary = json.loads((folder / "metrics.json").read_text(encoding="utf-8"))
    assert summary["ended"].endswith(", its pen never down: nothing written")
    assert summary["metrics"]["rmse_pen_down_m"] is None and summary["metrics"]["iou"] == 0.0
    assert report.event == "ended" and report.metrics is not None
    assert report.metrics.iou == 0.0 and report.metrics.rmse_pen_down_m is None


def test_a_job_ended_before_its_writing_began_reports_nothing_written(tmp_path: Path) -> None:
    run = _solo(tmp_path)
    _fly_until(run, lambda run: run.runner.phase == "transit")
    seen = _recording(run)
    _end(run, "land")
    run.tick()
    assert all(a.aborted is None for a in seen)  # nothing flown of its writing: no files
    (report,) = [r for a in seen for r in a.reports]
    assert report.event == "ended" and report.job_id == "j1"
    assert report.progress == 0.0 and report.metrics is None  # no figure of a writing
    assert report.error is not None and report.error.code == "landed_by_operator"
    assert report.error.message.endswith("at 0% of its plan, its pen never down: nothing written")
    assert not (run.setup.show.database_path.parent / "jobs").exists()


@pytest.mark.parametrize("answer", ["ok", "not_assigned"])
def test_the_answer_to_an_ended_report_touches_no_lease_and_no_running_job(
    monkeypatch: pytest.MonkeyPatch, answer: str
) -> None:
    """The vehicle holds j1 again (given back to it after it gave it up): the answer to its
    ``ended`` report of the earlier attempt neither renews that lease nor stops the job."""
    if answer == "ok":
        reply = CommandReply(ok=True, message="noted")
    else:
        info = ErrorInfo(code="not_assigned", message="j1 is not assigned to uav1; stop it")
        reply = CommandReply(ok=False, message=info.message, error=info)

    async def answered(*_args: object, **_kw: object) -> CommandReply:
        return reply

    monkeypatch.setattr(reports, "aquery_one", answered)
    lease, given_up = JobLease(lost_after_s=1.5), list[str]()
    lease.hold("j1", active=True, writing=False, now_s=10.0)
    outbox = ReportOutbox(
        ShowKeys("t"), "uav1", lease, retry_s=0.1, timeout_s=1.0,
        running_job=lambda: "j1", refused=given_up.append, settled=lambda _job: None,
    )  # fmt: skip
    ended = AgentReport(vehicle_id="uav1", job_id="j1", event="ended", progress=0.4)
    assert asyncio.run(outbox._deliver(None, ended))  # type: ignore[arg-type]
    assert lease.confirmed_at_s == 10.0 and given_up == []
    holding = AgentReport(vehicle_id="uav1", job_id="j1", event="holding")
    asyncio.run(outbox._deliver(None, holding))  # type: ignore[arg-type]
    assert lease.confirmed_at_s > 10.0 if answer == "ok" else given_up  # as any other report

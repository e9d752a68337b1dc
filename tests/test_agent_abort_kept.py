"""A job broken off after its writing began is measured, kept and told (issue 34).

The live agent (its service over real Zenoh in one process; the solo show's brush quadrotor in
the in-process sim; jobs planned, measured and recorded by the functions ``skyquill agent``'s
worker runs) is blown sideways a second into writing 一: the deviation abort's ``failed`` report
carries the metrics of what was flown, scored against the whole character (``flown_fraction``
below 1, an IoU below that of the same character written in full by the next agent); the job's
files are kept as a finished job's and ``skyquill replay`` reads them; and while the
orchestrator does not take the result, it waits in the results journal, metrics and all, across
a restart of the agent. Before, the runner dropped the trace: ``failed`` without metrics, no
files.
"""

from __future__ import annotations

import asyncio
import json
import threading
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from dataclasses import dataclass, replace
from pathlib import Path

import msgspec
import pytest
from job_traces import SHOWS

from bus.keys import ShowKeys
from bus.messages import AgentReport, CommandReply, JobAssignment, VehicleCommand
from bus.pubsub import declare_token
from bus.rpc import aquery_one, serve
from bus.session import BusSettings, Session, open_session
from cli.main import main as skyquill
from showfile import dump_show, load_show
from vehicle_agent.backends.base import Setpoint, VehicleSnapshot
from vehicle_agent.backends.sim import SimBackend, SimVehicle
from vehicle_agent.job_picture import PictureWorker
from vehicle_agent.job_runner import JobRunner
from vehicle_agent.jobs import archive_job, job_metrics, prepare_job
from vehicle_agent.service import AgentService
from vehicle_agent.service_settings import ServiceSettings
from vehicle_agent.setup import VehicleSetup, on_board, vehicle_setup
from vehicle_agent.work import ThreadJobWork

pytestmark = [pytest.mark.slow, pytest.mark.timeout(600)]

GUST_AFTER_S = 1.0
"""Pen-down flight in [s] before the gust begins."""
GUST_MPS, GUST_MAX_M = 1.0, 0.25
"""The gust moves the vehicle's reference sideways (+y) at this speed, up to this far: past the
show's deviation bound (0.15 m held 0.3 s), inside its fence."""


def _solo(tmp_path: Path) -> VehicleSetup:
    """uav1 of the solo show, its database (and so its job files) in ``tmp_path``."""
    show = load_show(SHOWS / "solo.yaml")
    storage = show.storage.model_copy(
        update={"database": tmp_path / "show.sqlite3", "job_files": "compact"}
    )
    return vehicle_setup(show.model_copy(update={"storage": storage}), "uav1")


class GustBackend(SimBackend):
    """The sim vehicle blown sideways from ``GUST_AFTER_S`` of pen-down flight on (``gust``
    False: calm): its loop follows the reference moved by the gust, so it leaves the stroke
    with the brush down; the push stays once the pen is up (it flies home blown aside)."""

    def __init__(self, setup: VehicleSetup, gust: bool) -> None:
        home = setup.show.vehicle(setup.vehicle_id).home_m_enu
        kind, settings = setup.kind, setup.settings
        super().__init__(SimVehicle(home, kind=kind, settings=settings,
                                    contact_region=on_board(setup)))  # fmt: skip
        self.gust, self.pen_down_s = gust, 0.0

    async def tick(self, setpoint: Setpoint | None, now_s: float) -> VehicleSnapshot:
        if setpoint is not None and self.gust:
            self.pen_down_s += self.vehicle.dt_s if setpoint.pen_down else 0.0
            push_m = min(max(0.0, self.pen_down_s - GUST_AFTER_S) * GUST_MPS, GUST_MAX_M)
            x, y, z = setpoint.position_m_enu
            setpoint = replace(setpoint, position_m_enu=(x, y + push_m, z))
        return await super().tick(setpoint, now_s)


@dataclass
class Orchestrator:
    """Presence, and a ``report`` queryable that records; results are refused (an internal
    error: the agent sends them again) until ``taking_results``."""

    session: Session
    keys: ShowKeys
    taking_results: bool = False

    def __post_init__(self) -> None:
        self.reports: list[AgentReport] = []
        self._lock = threading.Lock()
        self.token = declare_token(self.session, self.keys.orchestrator_alive)
        self.queryable = serve(self.session, self.keys.report("uav1"), AgentReport, self._on)

    def _on(self, report: AgentReport) -> CommandReply:
        if report.event in ("done", "failed") and not self.taking_results:
            raise RuntimeError("results are not taken now")
        with self._lock:
            self.reports.append(report)
        return CommandReply(ok=True)

    def result(self, job_id: str) -> AgentReport | None:
        with self._lock:
            ends = [r for r in self.reports if r.job_id == job_id and r.event in ("done", "failed")]
        return ends[-1] if ends else None

    async def assign(self, job_id: str) -> CommandReply:
        command = VehicleCommand(command="assign", job=JobAssignment(job_id=job_id, text="一"))
        key = self.keys.vehicle_assign("uav1")
        return await aquery_one(self.session, key, command, CommandReply, timeout_s=10.0)


async def wait_for(condition: Callable[[], bool], timeout_s: float = 240.0) -> None:
    async with asyncio.timeout(timeout_s):
        while not condition():
            await asyncio.sleep(0.05)


@asynccontextmanager
async def agent(
    setup: VehicleSetup, bus: BusSettings, results: Path, pictures: PictureWorker, *, gust: bool
) -> AsyncIterator[AgentService]:
    """uav1's agent on ``bus`` until the block ends (then stopped, as a restart would)."""
    settings = ServiceSettings(show_id=setup.show.show_id, zenoh=bus, time_scale=4.0,
                               report_retry_s=0.2, results_dir=results)  # fmt: skip
    work = ThreadJobWork(
        lambda assignment: prepare_job(setup, assignment),
        lambda prepared, trace: job_metrics(setup, prepared, trace),
        lambda prepared, trace, metrics: archive_job(setup, pictures, prepared, trace, metrics),
    )
    runner = JobRunner(setup.runner_config)
    service = AgentService(settings, runner, GustBackend(setup, gust), work)
    stop = asyncio.Event()
    task = asyncio.create_task(service.run(stop))
    try:
        await wait_for(lambda: service.runner.orchestrator_alive, 30.0)
        yield service
    finally:
        stop.set()
        await asyncio.wait_for(task, 30.0)


def _journaled(results: Path, job_id: str) -> AgentReport | None:
    path = results / f"{job_id}.json"
    return msgspec.json.decode(path.read_bytes(), type=AgentReport) if path.is_file() else None


def test_an_aborted_job_reports_its_partial_metrics_keeps_its_files_and_survives_a_restart(
    tmp_path: Path, free_tcp_port: Callable[[], int]
) -> None:
    setup, results = _solo(tmp_path), tmp_path / "results"
    pictures = PictureWorker("uav1")
    endpoint = f"tcp/127.0.0.1:{free_tcp_port()}"
    bus = BusSettings(router_listen=[endpoint], connect=[endpoint])

    async def scenario(orch: Orchestrator) -> tuple[AgentReport, AgentReport]:
        async with agent(setup, bus, results, pictures, gust=True) as first:
            assert (await orch.assign("j1")).ok
            await wait_for(
                lambda: (
                    first.runner.phase == "ground"
                    and (kept := _journaled(results, "j1")) is not None
                    and kept.metrics is not None
                )
            )
            assert first.results.pending() == "j1"  # its status names it until answered
        kept = _journaled(results, "j1")  # the agent is gone: only its journal knows
        assert kept is not None and orch.result("j1") is None
        async with agent(setup, bus, results, pictures, gust=False) as second:
            orch.taking_results = True
            await wait_for(lambda: orch.result("j1") is not None)
            assert orch.result("j1") == kept  # sent by the next agent, metrics and all
            await wait_for(lambda: not (results / "j1.json").exists())
            assert (await orch.assign("j2")).ok  # the same character, calm: written in full
            await wait_for(lambda: orch.result("j2") is not None)
            await wait_for(lambda: second.runner.phase == "ground")
        full = orch.result("j2")
        assert full is not None
        return kept, full

    with open_session(bus, role="router"), open_session(bus, role="client") as session:
        orch = Orchestrator(session, ShowKeys(setup.show.show_id))
        aborted, full = asyncio.run(scenario(orch))
    assert pictures.wait(240.0)

    assert aborted.event == "failed" and aborted.error is not None
    assert aborted.error.code == "deviation" and aborted.retry_after_s is None  # final: inked
    part, whole = aborted.metrics, full.metrics
    assert part is not None and whole is not None and whole.flown_fraction == 1.0
    assert 0.0 < part.flown_fraction < 1.0
    assert part.flown_fraction == pytest.approx(aborted.progress, abs=0.02)
    assert part.iou is not None and whole.iou is not None and whole.iou > 0.5
    assert part.iou < whole.iou, (part.iou, whole.iou)
    assert part.written is not None  # the kiosk shows the ink of a failed job from these

    folder = tmp_path / "jobs" / "j1-uav1-1"
    summary = json.loads((folder / "metrics.json").read_text(encoding="utf-8"))
    assert summary["label"] == "一" and summary["abort_reason"] == "deviation"
    assert summary["metrics"]["flown_fraction"] == pytest.approx(part.flown_fraction)
    assert (folder / "flight.npz").is_file() and (folder / "report.png").is_file()
    show_path = tmp_path / "solo.yaml"
    dump_show(setup.show, show_path)
    out = tmp_path / "j1.mcap"
    assert skyquill(["replay", str(show_path), "j1", "--out", str(out)]) == 0
    assert out.stat().st_size > 0

"""The agent's planning worker: a real worker process plans, measures and records jobs of the
Airshow show; its failures are clear job errors; it leaves no process behind; and the agent
process itself loads neither the planner's solvers nor matplotlib."""

from __future__ import annotations

import asyncio
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from job_traces import recorded_trace

from bus.messages import JobAssignment
from bus.rpc import error_info_from_exception
from cli.showrun import derived_show
from vehicle_agent.job_runner import PreparedJob
from vehicle_agent.plan_worker import PLAN_NICE
from vehicle_agent.trace import JobTrace
from vehicle_agent.work import JobWorkError
from vehicle_agent.worker_client import ProcessJobWork
from vehicle_agent.worker_protocol import SealedContext

ROOT = Path(__file__).resolve().parent.parent
AIRSHOW = ROOT / "shows" / "airshow-2014.yaml"
BUSY_PLAN_DEADLINE_S = 120.0
"""Generous: one character's plan takes 1-3 s on a quiet machine."""


def flown_as_planned(prepared: PreparedJob, board_z_m: float) -> JobTrace:
    """A trace that followed the plan exactly, the brush tip on the board while writing."""
    s = prepared.samples
    tip = s.position_m_enu.copy()
    tip[:, 2] = board_z_m
    width = np.where(s.pen_down, 0.02, 0.0)
    ref = s.position_m_enu
    return recorded_trace(
        prepared.job_id, 1, s.t_s, ref, s.velocity_mps_enu, ref, s.pen_down, s.pen_down, tip, width
    )


def gone(pid: int, timeout_s: float = 5.0) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            stat = Path(f"/proc/{pid}/stat").read_text()
        except FileNotFoundError:
            return True
        if stat.rsplit(")", 1)[1].split()[0] == "Z":
            return True  # a zombie: exited, not yet reaped
        time.sleep(0.05)
    return False


def test_planning_goes_on_while_every_core_is_busy(tmp_path: Path) -> None:
    """A loaded venue laptop: as many busy processes as cores beside the worker. In the idle
    scheduling class (before) the plan got no CPU at all and never came back."""
    _, show = derived_show(AIRSHOW, tmp_path)
    busy = [
        subprocess.Popen([sys.executable, "-c", "while True: pass"])
        for _ in range(os.cpu_count() or 2)
    ]

    async def scenario() -> None:
        work = ProcessJobWork(show, show.vehicles[0].id, 1.0)
        try:
            job = JobAssignment(job_id="j1", text="一")
            prepared = await asyncio.wait_for(work.prepare(job), BUSY_PLAN_DEADLINE_S)
            assert prepared.samples.pen_down.any()
        finally:
            await work.close()

    try:
        asyncio.run(scenario())
    finally:
        for process in busy:
            process.kill()
            process.wait()


def test_a_worker_plans_measures_and_records_a_job_and_stops_cleanly(tmp_path: Path) -> None:
    _, show = derived_show(AIRSHOW, tmp_path)
    vehicle = show.vehicles[0]
    board_z_m = show.board(vehicle.board).center_m_enu[2]

    async def scenario() -> None:
        work = ProcessJobWork(show, vehicle.id, 1.0)
        prepared = await work.prepare(JobAssignment(job_id="j1", text="一"))
        pid = work.pid
        assert pid is not None and pid != os.getpid() and work.starts == 1
        assert os.sched_getscheduler(pid) == os.SCHED_BATCH  # never preempts the loop
        niced = os.getpriority(os.PRIO_PROCESS, pid) - os.getpriority(os.PRIO_PROCESS, 0)
        assert niced == PLAN_NICE
        assert isinstance(prepared.context, SealedContext)
        assert prepared.samples.pen_down.any() and prepared.command_samples is not None
        assert work.last_cpu_s > 0.0
        trace = flown_as_planned(prepared, board_z_m)
        metrics = await work.measure(prepared, trace)
        assert metrics.rmse_pen_down_m == pytest.approx(0.0, abs=1e-6)
        assert metrics.iou is not None and metrics.iou > 0.5
        where = await work.archive(prepared, trace, metrics)
        assert isinstance(where, str) and (Path(where) / "metrics.json").is_file()
        await work.close()
        assert work.pid is None and gone(pid)
        assert (Path(where) / "report.png").is_file()  # drawn before the worker left

    asyncio.run(scenario())


def test_worker_failures_are_clear_job_errors_a_new_worker_takes_over_and_idle_ones_stop(
    tmp_path: Path,
) -> None:
    _, show = derived_show(AIRSHOW, tmp_path)

    async def scenario() -> None:
        work = ProcessJobWork(show, show.vehicles[0].id, 1.0, idle_exit_s=60.0)
        with pytest.raises(JobWorkError) as bad:
            await work.prepare(JobAssignment(job_id="j1", text="\u0378"))
        info = error_info_from_exception(bad.value)
        assert info.code == "plan_failed" and info.field == "text" and "U+0378" in info.message
        first = work.pid
        assert first is not None
        os.kill(first, 9)
        with pytest.raises(JobWorkError) as died:
            await work.prepare(JobAssignment(job_id="j2", text="一"))
        assert died.value.code == "worker_failed" and "exited" in str(died.value)
        prepared = await work.prepare(JobAssignment(job_id="j3", text="一"))
        assert prepared.job_id == "j3" and work.starts == 2
        # an idle worker stops by itself (the next job would start another)
        work.idle_exit_s = 0.3
        await work.prepare(JobAssignment(job_id="j4", text="一"))
        second = work.pid
        assert second is not None
        await asyncio.sleep(1.0)
        assert work.pid is None and gone(second)
        await work.close()

    asyncio.run(scenario())


def test_the_agent_process_loads_no_solver_and_no_plotting() -> None:
    """What ``skyquill agent`` imports up to flying a simulated vehicle (its planning worker
    imports the rest): none of the modules that made an idle agent 160 MiB."""
    probe = (
        "import sys\n"
        "from showfile import load_show\n"
        "from vehicle_agent.agent import make_backend, run_agent_blocking\n"
        "from vehicle_agent.setup import vehicle_setup\n"
        "import cli.cmd_agent\n"
        f"show = load_show({str(AIRSHOW)!r})\n"
        "setup = vehicle_setup(show, show.vehicles[0].id)\n"
        "make_backend(setup)\n"
        "heavy = ('scipy', 'matplotlib', 'piqp', 'clarabel', 'osqp', 'mujoco', 'casadi',\n"
        "         'cryptography', 'planner.pipeline', 'vehicle_agent.jobs')\n"
        "print(sorted(m for m in sys.modules if m.startswith(heavy)))\n"
    )
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    out = subprocess.run(
        [sys.executable, "-c", probe], env=env, capture_output=True, text=True, check=True
    )
    assert out.stdout.strip() == "[]"

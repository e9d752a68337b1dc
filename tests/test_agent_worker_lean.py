"""Issue 35: a planning worker kept for the show holds only what it reuses. A real worker plans,
measures and records jobs of the Airshow's quadrotors one after another, as at a show (each
job's record asked for before the last picture is drawn); every job gets its picture, drawn in
a process apart, and the worker itself has imported neither ``scipy.signal`` (0.6 s and 45 MiB
for one filter) nor matplotlib, nor the solvers and simulators of the other kinds."""

from __future__ import annotations

import asyncio
import time
from pathlib import Path

from test_agent_worker import AIRSHOW, flown_as_planned

from bus.messages import JobAssignment
from cli.showrun import derived_show
from vehicle_agent.job_picture import ORDER_NAME, PICTURE_NAME
from vehicle_agent.worker_client import ProcessJobWork

DRAW_DEADLINE_S = 240.0
"""Wall time allowed for three pictures (1-2 s of CPU each) on a loaded machine: the worker's
own wait on ``close`` is shorter (20 s), and what it leaves stays ordered on disk."""

NOT_FOR_A_QUADROTOR = ("scipy.signal", "matplotlib", "casadi", "mujoco")
"""Modules a quadrotor's worker must not hold: the tip filter's former import, the pictures'
plotting, the hexarotor's NLP solver and the MuJoCo worlds."""


def test_a_quadrotor_worker_pictures_every_job_apart_and_loads_no_plotting(
    tmp_path: Path,
) -> None:
    _, show = derived_show(AIRSHOW, tmp_path)
    vehicle = show.vehicles[0]
    board_z_m = show.board(vehicle.board).center_m_enu[2]

    async def scenario() -> tuple[list[Path], object]:
        work = ProcessJobWork(show, vehicle.id, 1.0)
        await work.warm()
        job_dirs = []
        try:
            for k, text in enumerate("永光马"):
                prepared = await work.prepare(JobAssignment(job_id=f"j{k}", text=text))
                trace = flown_as_planned(prepared, board_z_m)
                metrics = await work.measure(prepared, trace)
                job_dirs.append(Path(str(await work.archive(prepared, trace, metrics))))
            deadline = time.monotonic() + DRAW_DEADLINE_S
            while time.monotonic() < deadline and not all(_pictured(d) for d in job_dirs):
                await asyncio.sleep(0.2)
            loaded = await work.call(("loaded", NOT_FOR_A_QUADROTOR))
        finally:
            await work.close()
        return job_dirs, loaded

    job_dirs, loaded = asyncio.run(scenario())
    assert loaded == []
    assert [_pictured(d) for d in job_dirs] == [True] * 3


def _pictured(job_dir: Path) -> bool:
    return (job_dir / PICTURE_NAME).is_file() and not (job_dir / ORDER_NAME).exists()

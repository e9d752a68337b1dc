"""A show of all three vehicle kinds as separate processes over real Zenoh: two brush
quadrotors over boards, the wall hexarotor and a ground writer write at once, each job on its
own surface, each with its kind's figures in the done report."""

from __future__ import annotations

import threading
from pathlib import Path

import pytest
from show_probe import all_alive, snapshot_when

from bus.messages import Telemetry
from bus.pubsub import subscribe
from cli.showrun import ShowRun, derived_show, submit_texts, wait_for_jobs
from showfile import load_show

pytestmark = [pytest.mark.multiprocess, pytest.mark.slow, pytest.mark.timeout(300)]

MIXED = Path(__file__).resolve().parent.parent / "shows" / "mixed.yaml"
TIME_SCALE = 2.0  # MuJoCo worlds of the wall and ground vehicles on 2 busy cores
TEXTS = ["一", "I", "L", "十"]


def test_a_mixed_show_writes_on_boards_a_wall_and_the_floor_at_once(tmp_path: Path) -> None:
    path, show = derived_show(MIXED, tmp_path, time_scale=TIME_SCALE)
    forces: list[float] = []
    lock = threading.Lock()

    def on_telemetry(_key: str, message: Telemetry) -> None:
        if message.force_n is not None and message.force_n > 0.0:
            with lock:
                forces.append(message.force_n)

    with ShowRun(path, show, log_dir=tmp_path / "logs") as run, run.client() as session:
        wall_key = run.keys.telemetry("calligrapher")
        subscriber = subscribe(session, wall_key, Telemetry, on_telemetry)
        snapshot_when(session, run.keys, "every agent up", all_alive)  # they start in parallel
        replies = submit_texts(session, run.keys, TEXTS)
        jobs = wait_for_jobs(session, run.keys, [str(r.job_id) for r in replies], timeout_s=240.0)
        subscriber.undeclare()  # type: ignore[no-untyped-call]
    logs = {p.name: p.read_text(errors="replace")[-1500:] for p in (tmp_path / "logs").glob("*")}
    assert [j.state for j in jobs] == ["done"] * 4, (
        [(j.label, j.state, j.error) for j in jobs],
        logs,
    )
    by_vehicle = {j.vehicle_id: j for j in jobs}
    assert set(by_vehicle) == {"uav1", "uav2", "calligrapher", "ground1"}, by_vehicle
    for job in jobs:
        m = job.metrics
        assert m is not None and 0.0 < m.rmse_pen_down_m <= 0.02, (job.vehicle_id, m)
        assert m.iou is not None and m.iou >= 0.4, (job.vehicle_id, m)
    wall = by_vehicle["calligrapher"].metrics
    assert wall is not None and {"rmse_ee_m", "force_rmse_n"} <= set(wall.extra), wall
    assert 0.0 < wall.extra["force_rmse_n"] < 1.0, wall
    assert forces and 0.5 < max(forces) < 10.0, "no contact force in the wall's telemetry"
    ground = by_vehicle["ground1"].metrics
    assert ground is not None and ground.written is not None


def test_the_mixed_show_file_loads_with_its_kinds_on_their_surfaces() -> None:
    show = load_show(MIXED)
    kinds = {v.kind: show.board(v.board).orientation for v in show.vehicles}
    assert kinds == {"quadrotor-brush": "horizontal", "hexarotor-sponge": "vertical",
                     "omni-wheel": "floor"}  # fmt: skip

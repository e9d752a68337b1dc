"""A mixed show over real Zenoh: two vehicles in-process, two over MAVLink, all write characters.

The Airshow fleet with uav3 and uav4 switched to ``backend: mavlink``: the orchestrator and four
agent processes run as ``skyquill up`` runs them; the two MAVLink vehicles are simulated ArduCopters
in this process (as ``skyquill sim-mavlink`` serves them), at the show's time scale.
"""

from __future__ import annotations

import socket
from collections.abc import Iterator
from pathlib import Path

import pytest
from show_probe import all_alive, snapshot_when

from cli.showrun import ShowRun, derived_show, submit_texts, wait_for_jobs
from mavsim.config import STIFF_EPS, PositionGains
from mavsim.server import MavsimServer
from mavsim.show import vehicle_configs
from showfile import Show, dump_show, load_show

pytestmark = [pytest.mark.multiprocess, pytest.mark.slow, pytest.mark.timeout(240)]

AIRSHOW = Path(__file__).resolve().parent.parent / "shows" / "airshow-2014.yaml"
TIME_SCALE = 2.0  # MAVLink vehicles run on wall time: leave headroom on 2 busy cores
MAVLINK_VEHICLES = ("uav3", "uav4")


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def mixed_show(out: Path) -> tuple[Path, Show]:
    base = load_show(AIRSHOW)
    vehicles = []
    for index, vehicle in enumerate(base.vehicles):
        if vehicle.id in MAVLINK_VEHICLES:
            url = f"udp:127.0.0.1:{free_udp_port()}"
            update = {"backend": "mavlink", "mavlink_url": url, "mavlink_system_id": index + 1}
            vehicle = vehicle.model_copy(update=update)
        vehicles.append(vehicle)
    path, show = derived_show(
        AIRSHOW,
        out,
        time_scale=TIME_SCALE,
        vehicles=tuple(vehicles),
        controller=base.controller.model_copy(update={"preset": "default"}),
        # as shows/rehearsal-mavlink.yaml: behind an autopilot's position loop, the nominal pace
        planning=base.planning.model_copy(update={"pace": "nominal"}),
    )
    dump_show(show, path)
    return path, load_show(path)


@pytest.fixture
def simulated_vehicles(tmp_path: Path) -> Iterator[tuple[Path, Show]]:
    path, show = mixed_show(tmp_path)
    # the show's mechanics, not an autopilot's tune: the paper's stiff loop, unshaped (PX4's
    # position control; ArduCopter's shaped target trails the 0.6 m/s strokes of these 1.2 m
    # characters by 3 cm pen-down even on the stiff loop, measured)
    stiff = PositionGains.from_poles(STIFF_EPS)
    configs = vehicle_configs(show, position_source_delay_s=1.0, gains=stiff, autopilot="px4")
    with MavsimServer(configs, time_scale=TIME_SCALE):
        yield path, show


def test_two_in_process_and_two_mavlink_vehicles_write_a_show(
    simulated_vehicles: tuple[Path, Show], tmp_path: Path
) -> None:
    path, show = simulated_vehicles
    assert sorted(v.id for v in show.vehicles if v.backend == "mavlink") == list(MAVLINK_VEHICLES)
    with ShowRun(path, show, log_dir=tmp_path / "logs") as run, run.client() as session:
        snapshot_when(session, run.keys, "every agent up", all_alive)  # they start in parallel
        replies = submit_texts(session, run.keys, ["一", "L", "十", "I"])
        job_ids = [str(reply.job_id) for reply in replies]
        jobs = wait_for_jobs(session, run.keys, job_ids, timeout_s=150.0)
    logs = {p.name: p.read_text(errors="replace")[-2000:] for p in (tmp_path / "logs").glob("*")}
    assert [j.state for j in jobs] == ["done"] * 4, (
        [(j.label, j.state, j.error) for j in jobs],
        logs,
    )
    assert {j.vehicle_id for j in jobs} == {"uav1", "uav2", "uav3", "uav4"}, (
        [(j.label, j.vehicle_id, j.attempts) for j in jobs],
        logs,
    )
    for job in jobs:
        m = job.metrics
        assert m is not None and 0.0 < m.rmse_pen_down_m < 0.02, (job.vehicle_id, m)
        assert m.iou is not None and m.iou > 0.5, (job.vehicle_id, m)

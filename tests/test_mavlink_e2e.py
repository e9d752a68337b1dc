"""An agent writes a character through the MAVLink path, end to end, and as well as in-process.

The same pure agent code (JobRunner, prepare_job, job_metrics) flies one job twice: against the
in-process simulator backend, and over MAVLink/UDP against the simulated ArduCopter built from the
same show file (as ``skyquill sim-mavlink`` builds it). Only the bus is left out. The simulated
ArduCopter flies the paper's stiff position loop here (``--gains-eps 0.3``): this test is about the
MAVLink path, not the autopilot's tune (with ArduCopter's own shaped response mavsim writes 一 at
about 2 cm, as ArduCopter SITL does: ``benchmarks/bench_mavlink.py --writing``).
"""

from __future__ import annotations

import asyncio
import socket
from typing import Any

import pytest

from bus.messages import JobAssignment, JobMetrics, VehicleCommand
from mavsim.config import STIFF_EPS, PositionGains
from mavsim.server import MavsimServer
from mavsim.show import vehicle_configs
from showfile import parse_show
from vehicle_agent.agent import make_backend
from vehicle_agent.backends.base import VehicleBackend
from vehicle_agent.backends.mavlink.backend import MavlinkBackend
from vehicle_agent.clock import TickClock
from vehicle_agent.job_runner import JobRunner
from vehicle_agent.jobs import job_metrics, prepare_job
from vehicle_agent.setup import vehicle_setup

SCALE = 1.0
"""Vehicle and agent both run this many times faster than real time: as a vehicle flies. At 2x,
beside two busy cores, the paced loop stalled up to 40 ms and wrote 3.9-4.4 mm (8.0 mm once in
a fresh clone's CI, bound 7.45); at 1x 2.6-2.7 mm, for 9 s more of the test."""

SHOW = """
show_id: mavlink-e2e
boards:
  - {{id: b1, center_m_enu: [0.0, 0.0, 0.75], size_m: [1.4, 1.4], writing_area_m: [0.6, 0.6]}}
  - {{id: b2, center_m_enu: [2.0, 0.0, 0.75], size_m: [1.4, 1.4], writing_area_m: [0.6, 0.6]}}
vehicles:
  - {{id: sim1, backend: sim, board: b1, home_m_enu: [0.0, -1.0, 0.0]}}
  - {{id: mav1, backend: mavlink, mavlink_url: "udp:127.0.0.1:{port}", mavlink_system_id: 3,
     board: b2, home_m_enu: [2.0, -1.0, 0.0]}}
planning: {{write_height_m: 0.25, clearance_m: 0.05}}
"""


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


async def write_job(
    backend: VehicleBackend, setup: Any, text: str, *, paced: bool
) -> tuple[JobMetrics, float]:
    """The agent's control loop without the bus: assign, fly, measure; back on the ground.
    Also the longest step of agent time between two ticks in [s] (a stall skipped, paced)."""
    runner = JobRunner(setup.runner_config)
    assignment = JobAssignment(job_id="j1", text=text)
    prepared = prepare_job(setup, assignment)
    snapshot = await backend.start()
    assert runner.handle_command(VehicleCommand(command="assign", job=assignment), 0.0).ok
    # the agent's pacing (AgentService): a real vehicle's clock skips ahead after a stall
    clock = TickClock(backend.control_period_s, time_scale=SCALE, skip_when_late=True)
    metrics: JobMetrics | None = None
    previous_s, longest_step_s = 0.0, 0.0
    while clock.now_s < 60.0:
        if paced:
            await asyncio.sleep(clock.delay_s())
        now = clock.now_s
        longest_step_s, previous_s = max(longest_step_s, now - previous_s), now
        actions = runner.step(snapshot, now)
        if actions.plan_request is not None:
            runner.plan_ready(prepared)
        assert not any(r.event == "failed" for r in actions.reports), actions.reports
        assert actions.aborted is None, actions.aborted.report
        if actions.backend_command is not None:
            name, hover = actions.backend_command
            await (backend.takeoff(hover) if name == "takeoff" else backend.land())  # type: ignore[arg-type]
        snapshot = await backend.tick(actions.setpoint, now)
        if actions.finished is not None:
            metrics = job_metrics(setup, prepared, actions.finished)
        if metrics is not None and runner.phase == "ground":
            await backend.close()
            return metrics, longest_step_s
        clock.advance()
    raise AssertionError(f"job not finished: runner {runner.state}/{runner.phase}, {snapshot}")


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_a_character_written_over_mavlink_matches_the_in_process_simulator() -> None:
    show = parse_show(SHOW.format(port=free_udp_port()))
    configs = vehicle_configs(
        show, position_source_delay_s=0.0, gains=PositionGains.from_poles(STIFF_EPS)
    )
    assert [(c.vehicle_id, c.system_id) for c in configs] == [("mav1", 3)]

    sim_setup = vehicle_setup(show, "sim1")
    in_process, _ = asyncio.run(write_job(make_backend(sim_setup), sim_setup, "一", paced=False))

    mav_setup = vehicle_setup(show, "mav1", time_scale=SCALE)
    backend = make_backend(mav_setup)
    assert isinstance(backend, MavlinkBackend)
    with MavsimServer(configs, time_scale=SCALE) as server:
        over_mavlink, longest_step_s = asyncio.run(write_job(backend, mav_setup, "一", paced=True))
        autopilot = server.endpoints[0].autopilot
        assert not autopilot.armed and autopilot.on_ground
        assert autopilot.setpoints_received > 0.9 * backend.setpoints_sent > 100
        behind_s = server.longest_behind_s - autopilot.airframe.dt_s  # a step is due each loop
        physics_behind_s = max(0.0, behind_s)

    for name, m in (("in-process", in_process), ("over MAVLink", over_mavlink)):
        print(f"\n{name}: rmse pen down {m.rmse_pen_down_m * 1000:.1f} mm,", end=" ")
        print(f"max {m.max_error_m * 1000:.1f} mm, IoU {m.iou:.3f}", end="")
    print()
    print(f"longest control step {longest_step_s * 1000:.0f} ms of agent time;", end=" ")
    print(f"the simulator's physics {physics_behind_s * 1000:.0f} ms more than a step behind")
    assert over_mavlink.duration_s == pytest.approx(in_process.duration_s, abs=0.05)
    assert in_process.rmse_pen_down_m < 0.01
    # What the reference moves (at most v_max) while a loaded host stalls the paced loop (a
    # real vehicle's loop skips those ticks: its error is real) or the simulator's thread (the
    # vehicle flies its last setpoint meanwhile): a fresh clone's CI once wrote 8.9 mm (bound
    # 7.5), where 2.6-4.6 mm are written alone and 2.5-3.2 mm beside three busy loops, neither
    # stalled beyond 2 ms (2026-12-02).
    stalled_s = max(0.0, longest_step_s - backend.control_period_s, physics_behind_s)
    stall_m = show.vehicle_limits("mav1").v_max_mps * stalled_s
    # the same character, within a small margin of the in-process flight
    assert over_mavlink.rmse_pen_down_m < in_process.rmse_pen_down_m + 0.005 + stall_m
    # the worst sample: 10 mm more
    assert over_mavlink.max_error_m < in_process.max_error_m + 0.01 + stall_m
    assert in_process.iou is not None and over_mavlink.iou is not None  # brush from the pose
    assert over_mavlink.iou > in_process.iou - 0.05

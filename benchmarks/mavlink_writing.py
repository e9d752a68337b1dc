"""One character written by the agent's own job code, per autopilot: pen-down RMSE and ink IoU.

The pure agent code (JobRunner, prepare_job, job_metrics; the bus left out) flies one job on one
board against each target: ``sim`` (the in-process simulator), ``mavsim`` (the project's
simulated ArduCopter over UDP), ``ardupilot`` and ``px4`` (real SITL started with
scripts/sitl/start.py from $SKYQUILL_ARDUCOPTER_SITL / $SKYQUILL_PX4_SITL, flying on the
simulator's truth as mocap, metrics from the truth). Used by ``bench_mavlink.py --writing`` and
the SITL tests.
"""

from __future__ import annotations

import asyncio
import importlib.util
import os
import shutil
import socket
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

from bus.messages import JobAssignment, JobMetrics, VehicleCommand
from showfile import load_show, parse_show
from vehicle_agent.agent import make_backend
from vehicle_agent.backends.base import CommandRefusedError, VehicleBackend
from vehicle_agent.backends.mavlink.backend import MavlinkBackend
from vehicle_agent.clock import TickClock
from vehicle_agent.job_runner import JobRunner
from vehicle_agent.jobs import job_metrics, planned_job, prepared_job
from vehicle_agent.setup import vehicle_setup

ROOT = Path(__file__).resolve().parents[1]
HOME_M_ENU = (0.0, -1.0, 0.0)
SITL_SYSTEM_ID = 8
"""System id of the SITL autopilot (start.py picks a free instance number and ports)."""
SITL_MOCAP = {"ardupilot": "vision_position_estimate", "px4": "odometry"}
"""How each autopilot gets the mocap: PX4 SIH hovers within 1-1.5 cm only with the mocap's
velocity fused (ODOMETRY); ArduCopter writes as well on the position alone."""
SHOW = """
show_id: mavlink-writing
boards:
  - {{id: b1, center_m_enu: [0.0, 0.0, 0.75], size_m: [1.4, 1.4], writing_area_m: [0.6, 0.6]}}
vehicles:
  - {{id: v1, board: b1, home_m_enu: [0.0, -1.0, 0.0], {vehicle}}}
planning: {{write_height_m: 0.25, clearance_m: 0.05, pace: {pace}{first}}}
storage: {{database: {database}}}
"""
TARGETS = ("sim", "rotorpy", "mavsim", "ardupilot", "px4")
SITL_SHOWS = {"ardupilot": ROOT / "shows/sitl-ardupilot.yaml", "px4": ROOT / "shows/sitl-px4.yaml"}
"""The shipped show of each autopilot: its pace settings are the ones the SITL targets fly."""
WARM_UP_S = 8.0
"""An autopilot's least time on the ground after connect (mocap fused, sources switched)."""
READY_LIMIT_S = 240.0
"""Longest wait in [s] after connect for an autopilot to say its pre-arm checks pass (ArduCopter
fusing forwarded mocap: its EKF takes about 40 s, and mocap flows only once the agent is on)."""


@dataclass(frozen=True)
class Written:
    """What one target wrote."""

    target: str
    metrics: JobMetrics
    lead_s: float | None
    """The lead in [s] the backend applied at the end (None: not a MAVLink backend)."""


def launcher() -> ModuleType:
    """scripts/sitl/start.py, imported by path (once)."""
    if "sitl_start" in sys.modules:
        return sys.modules["sitl_start"]
    spec = importlib.util.spec_from_file_location("sitl_start", ROOT / "scripts/sitl/start.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["sitl_start"] = module
    spec.loader.exec_module(module)
    return module


def sitl_available(kind: str) -> bool:
    return bool(os.environ.get(launcher().ENV_BINARY[kind]))


async def fly_jobs(
    backend: VehicleBackend, setup: Any, texts: list[str], *, paced: bool, limit_s: float = 240.0
) -> list[JobMetrics]:
    """The agent's control loop without the bus: start the backend, then for each text assign,
    fly, measure, back on the ground (the next job on the same vehicle, as a show runs).
    ``paced``: in real time (an autopilot); otherwise as fast as the simulator goes."""
    assignments = [JobAssignment(job_id=f"j{k}", text=text) for k, text in enumerate(texts)]
    # Planned before connecting: planning inside the loop stalled it, and the mocap stream, for
    # 1.2 s before take-off (PX4 dropped external vision); the agent plans in a worker process.
    # Each is paced just before it flies, with the tracking identified on the jobs before it.
    plans = [planned_job(setup, a) for a in assignments]
    snapshot = await backend.start()
    clock = TickClock(backend.control_period_s, time_scale=1.0, skip_when_late=True)
    while paced and not _warm(backend, clock.now_s):  # the EKF converges on the forwarded mocap
        if clock.now_s > READY_LIMIT_S:
            raise RuntimeError(f"the autopilot's pre-arm checks do not pass {READY_LIMIT_S:.0f} s "
                               f"after connect: {_last_texts(backend)}")  # fmt: skip
        await asyncio.sleep(clock.delay_s())
        snapshot = await backend.tick(None, clock.now_s)
        clock.advance()
    done: list[JobMetrics] = []
    runner = JobRunner(setup.runner_config)  # one per vehicle, as the agent has
    for k, (assignment, plan) in enumerate(zip(assignments, plans, strict=True)):
        prepared = prepared_job(setup, assignment.job_id, plan)
        if not runner.handle_command(VehicleCommand(command="assign", job=assignment),
                                     clock.now_s).ok:  # fmt: skip
            raise RuntimeError(f"the runner refused job {k}")
        metrics: JobMetrics | None = None
        t_end = clock.now_s + limit_s
        while metrics is None or runner.phase != "ground":
            if clock.now_s > t_end:
                raise RuntimeError(f"job {k} not done in {limit_s:.0f} s: {runner.phase}")
            if paced:
                await asyncio.sleep(clock.delay_s())
            now = clock.now_s
            actions = runner.step(snapshot, now)
            if actions.plan_request is not None:
                runner.plan_ready(prepared)
            failed = [r for r in actions.reports if r.event == "failed"]
            if failed:
                raise RuntimeError(f"job {k} failed: {failed[0]}")
            if actions.aborted is not None:  # its failed report waits for the metrics
                raise RuntimeError(f"job {k} failed: {actions.aborted.report}")
            if actions.backend_command is not None:
                name, hover = actions.backend_command
                if name == "takeoff":
                    await _take_off(backend, hover, clock)
                    now = clock.now_s
                else:
                    await backend.land()
            snapshot = await backend.tick(actions.setpoint, now)
            if snapshot.fault is not None:
                raise RuntimeError(f"job {k}: vehicle fault: {snapshot.fault}")
            if actions.finished is not None:
                metrics = job_metrics(setup, prepared, actions.finished)
            clock.advance()
        done.append(metrics)
    return done


async def _take_off(backend: VehicleBackend, hover: Any, clock: TickClock) -> None:
    """Take off; a refusal (pre-arm checks) is tried again every 2 s for up to a minute, the
    backend ticked meanwhile (mocap flowing), as the agent does with its back-off."""
    t_end = clock.now_s + 60.0
    while True:
        try:
            await backend.takeoff(hover)
            return
        except CommandRefusedError:
            if clock.now_s > t_end:
                raise
        t_retry = clock.now_s + 2.0
        while clock.now_s < t_retry:
            await asyncio.sleep(clock.delay_s())
            await backend.tick(None, clock.now_s)
            clock.advance()


def _warm(backend: VehicleBackend, now_s: float) -> bool:
    """Past the warm-up and, on a MAVLink autopilot, its pre-arm checks passing."""
    if now_s < WARM_UP_S:
        return False
    return not isinstance(backend, MavlinkBackend) or backend.state.prearm_good is not False


def _last_texts(backend: VehicleBackend) -> list[str]:
    return [text for _, text in backend.events][-5:] if isinstance(backend, MavlinkBackend) else []


def show_of(vehicle: str, pace: str = "tracking", first_stretch: float | None = None) -> Any:
    """The one-board show of ``vehicle`` (its show-file fields) at ``pace``, its first job
    ``first_stretch`` times slower than the limits (None: the show file's default); its database,
    and so the vehicle's tracking model, in a fresh temporary folder: every run identifies anew."""
    database = Path(tempfile.mkdtemp(prefix="skyquill-writing-")) / "show.sqlite3"
    first = "" if first_stretch is None else f", pace_first_stretch: {first_stretch}"
    return parse_show(SHOW.format(vehicle=vehicle, pace=pace, first=first, database=database))


def write(target: str, texts: list[str]) -> list[Written]:
    """Fly ``texts`` one after the other on ``target`` (one of :data:`TARGETS`), each paced to
    the tracking identified on the ones before it (the first at the cautious first pace)."""
    if target == "sim":
        setup = vehicle_setup(show_of("backend: sim"), "v1")
        flown = asyncio.run(fly_jobs(make_backend(setup), setup, texts, paced=False))
        return [Written(target, m, None) for m in flown]
    if target == "rotorpy":  # RotorPy's SE3 controller on PX4 SIH's airframe (beside this file)
        from rotorpy_writing import write_rotorpy

        return [Written(target, m, None) for m in write_rotorpy(show_of("backend: sim"), texts)]
    if target == "mavsim":
        return _write_mavsim(texts)
    return _write_sitl(target, texts)


def _write_mavsim(texts: list[str]) -> list[Written]:
    from mavsim.server import MavsimServer
    from mavsim.show import vehicle_configs

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(("127.0.0.1", 0))
        port = int(sock.getsockname()[1])
    vehicle = f'backend: mavlink, mavlink_url: "udp:127.0.0.1:{port}", mavlink_system_id: 1'
    show = show_of(vehicle)
    with MavsimServer(vehicle_configs(show, position_source_delay_s=0.0)):
        return _fly_mavlink("mavsim", show, texts)


def _write_sitl(kind: str, texts: list[str]) -> list[Written]:
    launch = launcher()
    binary = launch.binary_for(kind)
    run_dir = Path(tempfile.mkdtemp(prefix=f"skyquill-writing-{kind}-"))
    vibration = launch.RESEARCH_AIRFRAME_VIBRATION if kind == "px4" else None  # start.py's default
    inst = launch.claim_instance(kind, SITL_SYSTEM_ID, launch.home_lla(HOME_M_ENU), binary,
                                 run_dir, mocap=True, imu_vibration=vibration)  # fmt: skip
    process = launch.start(inst)
    try:
        if kind == "ardupilot":  # its EKF waits for the mocap the agent forwards: the agent waits
            _wait_port(inst.url, process)
        else:
            launch.wait_ready(inst, process, launch.READY_TIMEOUT_S)
        vehicle = (
            f'backend: mavlink, mavlink_url: "{inst.url}", mavlink_system_id: {inst.system_id}, '
            f"mavlink_truth: sitl, mavlink_mocap: {SITL_MOCAP[kind]}"
        )
        first = load_show(SITL_SHOWS[kind]).planning.pace_first_stretch
        return _fly_mavlink(kind, show_of(vehicle, first_stretch=first), texts)
    finally:
        launch.stop(process)
        if not os.environ.get("SKYQUILL_KEEP_SITL_RUN"):
            shutil.rmtree(run_dir, ignore_errors=True)


def _wait_port(url: str, process: Any, timeout_s: float = 30.0) -> None:
    """Wait until the TCP port of ``url`` (``tcp:HOST:PORT``) accepts a connection."""
    host, port = url.split(":")[1:3]
    deadline = time.monotonic() + timeout_s
    while process.poll() is None and time.monotonic() < deadline:
        try:
            with socket.create_connection((host, int(port)), timeout=1.0):
                return
        except OSError:
            time.sleep(0.5)
    raise RuntimeError(f"SITL port {url} did not open within {timeout_s:.0f} s")


def _fly_mavlink(target: str, show: Any, texts: list[str]) -> list[Written]:
    setup = vehicle_setup(show, "v1")
    backend = make_backend(setup)

    async def run() -> list[Written]:
        try:
            flown = await fly_jobs(backend, setup, texts, paced=True)
        finally:
            await backend.close()
        lead_s = backend.aid.lead_s if isinstance(backend, MavlinkBackend) else None
        return [Written(target, m, lead_s) for m in flown]

    return asyncio.run(run())

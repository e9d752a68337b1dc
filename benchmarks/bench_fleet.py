"""Fleet numbers: cost of one agent's control tick, and a whole simulated show's throughput.

    .venv/bin/python benchmarks/bench_fleet.py [--text 永] [--show-scale 4] [--characters 8]
        [--skip-show] [--peer-rev f946860]

1. Control tick: the agent's job runner + the in-process simulator (SIM world + RPT controller)
   writing one character, no bus: microseconds per 100 Hz tick, hence the largest ``time_scale``
   one core sustains for one agent (the loop runs in lock step: beyond it the show runs slower);
   and for the writing ticks alone, split between the runner (``JobRunner.step``) and the
   simulated vehicle (its world, controller and brush, ``SimVehicle.tick``). With
   ``--peer-rev`` the same tick measured on that git revision (exported with ``git archive``,
   run in turns with this tree, best of three each) and the ratio.
2. Fleet tick: ``--fleet`` vehicles writing at once in one process, in lock step as a fleet
   host's shared ticker wakes them: CPU microseconds per vehicle-tick with their simulated
   vehicles stepped together (one :class:`vehicles.quadrotor_brush.loop.QuadrotorFleet`) and,
   the peer in the same run, each stepped alone.
3. Show: the Airshow show (orchestrator + four agent processes, real Zenoh on loopback) at
   ``--show-scale``; characters submitted at once; wall time until all are written.

Measured on the shared 2-core machine under ``nice -n 15`` (others' load average 2-8, so
figures move by 20-40 % between runs; compare within one run):

- control tick of one agent (永, 3,610 ticks): 285 us against 331 us for f946860 in the same run
  (ratio 0.86; 240-256 against 292-303 in alternate runs); a writing tick: runner 45-55 us
  (1.2-1.6x less than f946860's in alternate runs: surface basis, board test, geofence edges
  and reference interpolation in floats) + simulated vehicle 205-250 us (its world, controller
  and brush on one row of numpy arrays);
- 20 vehicles writing 一 at once in lock step: 435 us of CPU per vehicle-tick each stepped
  alone, 59 us stepped together (x7.4); 10 at once: 321 against 59 (x5.5).
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bus.messages import JobAssignment, VehicleCommand  # noqa: E402
from cli.showrun import ShowRun, derived_show, submit_texts, wait_for_jobs  # noqa: E402
from showfile import load_show  # noqa: E402
from vehicle_agent.agent import make_backend  # noqa: E402
from vehicle_agent.backends.sim import SimBackend  # noqa: E402
from vehicle_agent.backends.sim_round import StepRounds  # noqa: E402
from vehicle_agent.job_runner import JobRunner  # noqa: E402
from vehicle_agent.jobs import prepare_job  # noqa: E402
from vehicle_agent.setup import vehicle_setup  # noqa: E402

AIRSHOW = ROOT / "shows" / "airshow-2014.yaml"
TEXTS = ["一", "L", "二", "十", "I", "T", "V", "Z", "永", "A", "光", "马"]


@dataclass(frozen=True)
class TickCost:
    """What one character's flight cost, in microseconds of CPU-bound wall time per tick."""

    us_per_tick: float
    """All ticks, from the job's assignment to the landing."""
    ticks: int
    """How many 100 Hz ticks the job took."""
    planned_s: float
    """Planned writing time in [s]."""
    write_runner_us: float
    """Per writing tick: ``JobRunner.step`` (reference, safety, trace, telemetry)."""
    write_vehicle_us: float
    """Per writing tick: ``SimVehicle.tick`` (world, controller, brush, snapshot)."""


def tick_cost(text: str) -> TickCost:
    """The control tick of one character flown in-process, from assignment to landing."""
    setup = vehicle_setup(load_show(AIRSHOW), "uav1")
    backend = make_backend(setup)
    assert isinstance(backend, SimBackend)
    vehicle = backend.vehicle
    runner = JobRunner(setup.runner_config)
    prepared = prepare_job(setup, JobAssignment(job_id="b", text=text))
    runner.set_orchestrator_alive(True, 0.0)
    runner.handle_command(VehicleCommand(command="assign", job=JobAssignment(job_id="b")), 0.0)
    runner.plan_ready(prepared)
    snapshot = vehicle.snapshot()
    ticks = writing = 0
    runner_s = vehicle_s = 0.0
    clock = time.perf_counter
    started = clock()
    while ticks < 10 or runner.phase != "ground":
        t0 = clock()
        actions = runner.step(snapshot, ticks * vehicle.dt_s)
        if actions.backend_command is not None:
            name, hover = actions.backend_command
            getattr(vehicle, name)(*(() if hover is None else (hover,)))
        t1 = clock()
        snapshot = vehicle.tick(actions.setpoint)
        if runner.phase == "write":
            writing += 1
            runner_s += t1 - t0
            vehicle_s += clock() - t1
        ticks += 1
    elapsed = clock() - started
    return TickCost(
        elapsed / ticks * 1e6,
        ticks,
        prepared.samples.duration_s,
        runner_s / max(writing, 1) * 1e6,
        vehicle_s / max(writing, 1) * 1e6,
    )


def fleet_tick_us(text: str, count: int, *, together: bool) -> float:
    """CPU microseconds per vehicle-tick of ``count`` vehicles writing ``text`` at once in one
    process, in lock step (runners, then the simulated vehicles), from assignment to landing:
    their simulated vehicles stepped together (one fleet, as a fleet host does) or each alone."""
    setup = vehicle_setup(load_show(AIRSHOW), "uav1")
    prepared = prepare_job(setup, JobAssignment(job_id="b", text=text))
    rounds = StepRounds() if together else None
    vehicles, runners = [], []
    for seed in range(count):
        backend = make_backend(setup, seed=seed, rounds=rounds)
        assert isinstance(backend, SimBackend)
        vehicles.append(backend.vehicle)
        runner = JobRunner(setup.runner_config)
        runner.set_orchestrator_alive(True, 0.0)
        runner.handle_command(VehicleCommand(command="assign", job=JobAssignment(job_id="b")), 0.0)
        runner.plan_ready(prepared)
        runners.append(runner)
    fleet = vehicles[0].fleet
    snapshots = [v.snapshot() for v in vehicles]
    ticks = 0
    started = time.process_time()
    while ticks < 10 or any(r.phase != "ground" for r in runners):
        for runner, vehicle, snapshot in zip(runners, vehicles, snapshots, strict=True):
            actions = runner.step(snapshot, ticks * vehicle.dt_s)
            if actions.backend_command is not None:
                name, hover = actions.backend_command
                getattr(vehicle, name)(*(() if hover is None else (hover,)))
            vehicle.begin_tick(actions.setpoint)
        if fleet is not None:
            fleet.step()
        snapshots = [v.end_tick() for v in vehicles]
        ticks += 1
    return (time.process_time() - started) / (ticks * count) * 1e6


def peer_tick_us(rev: str, text: str, tree: Path) -> float:
    """Microseconds per control tick of this benchmark as it was at ``rev`` (exported once into
    ``tree``), in a child process."""
    if not (tree / "benchmarks").exists():
        archive = subprocess.run(
            ["git", "-C", str(ROOT), "archive", rev], check=True, capture_output=True
        ).stdout
        subprocess.run(["tar", "-x", "-C", str(tree)], input=archive, check=True)
    out = subprocess.run(
        [sys.executable, "benchmarks/bench_fleet.py", "--skip-show", "--text", text],
        cwd=tree,
        env={**os.environ, "PYTHONPATH": str(tree)},
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    found = re.search(r"(\d+) us/tick", out)
    if found is None:
        raise RuntimeError(f"no tick cost in the output of {rev}: {out!r}")
    return float(found.group(1))


def show_throughput(scale: float, count: int) -> None:
    texts = (TEXTS * (1 + count // len(TEXTS)))[:count]
    with tempfile.TemporaryDirectory() as tmp:
        path, show = derived_show(AIRSHOW, Path(tmp), time_scale=scale)
        started = time.monotonic()
        with ShowRun(path, show, log_dir=Path(tmp) / "logs") as run, run.client() as session:
            replies = submit_texts(session, run.keys, texts)
            jobs = wait_for_jobs(
                session, run.keys, [str(r.job_id) for r in replies], timeout_s=900.0
            )
        wall = time.monotonic() - started
    done = [j for j in jobs if j.state == "done"]
    written_s = sum(j.metrics.duration_s for j in done if j.metrics is not None)
    print(
        f"show: {len(done)}/{len(jobs)} characters written in {wall:.1f} s wall at "
        f"time_scale {scale:g} (incl. process start); {written_s:.0f} s of writing in all"
    )
    per_vehicle: dict[str, float] = {}
    for job in done:
        if job.metrics is not None and job.vehicle_id is not None:
            per_vehicle[job.vehicle_id] = per_vehicle.get(job.vehicle_id, 0.0) + 1.0
    print(f"      jobs per vehicle: {dict(sorted(per_vehicle.items()))}")
    rmse = [j.metrics.rmse_pen_down_m * 1000 for j in done if j.metrics is not None]
    if rmse:
        print(
            f"      RMSE pen down: median {statistics.median(rmse):.1f} mm, max {max(rmse):.1f} mm"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--text", default="永")
    parser.add_argument("--show-scale", type=float, default=4.0)
    parser.add_argument("--characters", type=int, default=8)
    parser.add_argument("--skip-show", action="store_true")
    parser.add_argument("--peer-rev", help="git revision whose control tick to measure beside")
    parser.add_argument("--fleet", type=int, default=20, help="vehicles writing at once (0: no)")
    parser.add_argument("--fleet-text", default="一")
    args = parser.parse_args()
    if args.peer_rev is None:
        cost = tick_cost(args.text)
    else:
        with tempfile.TemporaryDirectory() as tmp:
            runs = [
                (peer_tick_us(args.peer_rev, args.text, Path(tmp)), tick_cost(args.text))
                for _ in range(3)
            ]
        cost = min((c for _, c in runs), key=lambda c: c.us_per_tick)
    us = cost.us_per_tick
    print(
        f"control tick (runner + sim, {args.text!r}, {cost.planned_s:.1f} s planned, "
        f"{cost.ticks} ticks): {us:.0f} us/tick -> one core sustains time_scale "
        f"{1e6 / (100 * us):.1f} for one agent"
    )
    print(
        f"      writing tick: runner {cost.write_runner_us:.0f} us + simulated vehicle "
        f"{cost.write_vehicle_us:.0f} us"
    )
    if args.peer_rev is not None:
        peer_us = min(p for p, _ in runs)
        print(
            f"      peer {args.peer_rev}: {peer_us:.0f} us/tick; this tree / peer "
            f"{us / peer_us:.2f} (best of {len(runs)} each, in turns)"
        )
    if args.fleet > 0:
        alone = fleet_tick_us(args.fleet_text, args.fleet, together=False)
        together = fleet_tick_us(args.fleet_text, args.fleet, together=True)
        print(
            f"{args.fleet} vehicles writing {args.fleet_text!r} at once (lock step, CPU time): "
            f"{alone:.0f} us per vehicle-tick each stepped alone, {together:.0f} us stepped "
            f"together (alone / together {alone / together:.2f})"
        )
    if not args.skip_show:
        show_throughput(args.show_scale, args.characters)


if __name__ == "__main__":
    main()

"""Fleet numbers: cost of one agent's control tick, and a whole simulated show's throughput.

    .venv/bin/python benchmarks/bench_fleet.py [--text 永] [--show-scale 4] [--characters 8]

1. Control tick: the agent's job runner + the in-process simulator (SIM world + RPT controller)
   writing one character, no bus: microseconds per 100 Hz tick, hence the largest ``time_scale``
   one core sustains for one agent (the loop runs in lock step: beyond it the show runs slower).
2. Show: the Airshow show (orchestrator + four agent processes, real Zenoh on loopback) at
   ``--show-scale``; characters submitted at once; wall time until all are written.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bus.messages import JobAssignment, VehicleCommand  # noqa: E402
from cli.showrun import ShowRun, derived_show, submit_texts, wait_for_jobs  # noqa: E402
from showfile import load_show  # noqa: E402
from vehicle_agent.agent import make_backend, prepare_job, vehicle_setup  # noqa: E402
from vehicle_agent.backends.sim import SimBackend  # noqa: E402
from vehicle_agent.job_runner import JobRunner  # noqa: E402

AIRSHOW = ROOT / "shows" / "airshow-2014.yaml"
TEXTS = ["一", "L", "二", "十", "I", "T", "V", "Z", "永", "A", "光", "马"]


def tick_cost(text: str) -> tuple[float, int, float]:
    """(microseconds per tick, ticks, planned duration) of one character flown in-process."""
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
    ticks = 0
    started = time.perf_counter()
    while ticks < 10 or runner.phase != "ground":
        actions = runner.step(snapshot, ticks * vehicle.dt_s)
        if actions.backend_command is not None:
            name, hover = actions.backend_command
            getattr(vehicle, name)(*(() if hover is None else (hover,)))
        snapshot = vehicle.tick(actions.setpoint)
        ticks += 1
    elapsed = time.perf_counter() - started
    return elapsed / ticks * 1e6, ticks, prepared.samples.duration_s


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
    args = parser.parse_args()
    us, ticks, duration = tick_cost(args.text)
    print(
        f"control tick (runner + sim, {args.text!r}, {duration:.1f} s planned, {ticks} ticks): "
        f"{us:.0f} us/tick -> one core sustains time_scale {1e6 / (100 * us):.1f} "
        f"for one agent"
    )
    if not args.skip_show:
        show_throughput(args.show_scale, args.characters)


if __name__ == "__main__":
    main()

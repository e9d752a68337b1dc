"""Show throughput: characters per hour of the Airshow show, today's default pace beside the new.

    python benchmarks/bench_show.py            # 20 characters (8 Latin, 12 Chinese)
    python benchmarks/bench_show.py --quick    # 4 characters (smoke run)
    python benchmarks/bench_show.py --day      # also 8 hours of a show day (show_day.py)

Each character is laid out and planned as a vehicle agent of ``shows/airshow-2014.yaml`` does it
(``vehicles.jobs.job_setup``: the show's board, writing area and margin, and the brush room's
settings of the vehicle, its limits and planning section),
once at the ``"nominal"`` pace (the planner's default before issue 15: every leg at 0.6 v_max and
half the smallest acceleration limit) and once at the new default ``"limits"`` pace. A vehicle
flies every job through the same phases (vehicle_agent.job_runner): take-off climb to the pen-up
height above home, transit to the start of the plan, settle, write, return above home, land.
Only the writing changes with the pace. Durations are computed, not simulated:

- climb / land: the in-process sim's autopilot moves (vehicle_agent.backends.sim): straight
  minimum-jerk quintics at 0.5 m/s and 0.8 m/s^2 vertically (``VERTICAL_*`` below);
- transit / return: the agent's quintic moves (vehicle_agent.motion) at the show's v_max and
  its smallest acceleration limit;
- settle: not counted (the sim's closed loop is within the 1 cm tolerance a few ticks after the
  transit ends); planning itself is counted (it runs on the ground before take-off).

Characters per hour for the show's four vehicles, each writing on its own board, one character
after another: ``4 * 3600 / mean(cycle)``.

ETAs (``--eta``, a real run): the Airshow show (router, orchestrator, four simulated agents as
child processes, real Zenoh on loopback) at ``--eta-scale``; the corpus is submitted at once
once every vehicle is ready, and after ``--settle`` seconds (planned durations replace the rough
estimates) one snapshot gives each queued job's ETA. The show's crew is the benchmark's
Stagehand, and the show is told its turnaround (``STAGEHAND_TURNAROUND_S``). Predicted start =
snapshot time + ETA; predicted finish = predicted start + the job's planned duration (as the
vehicle reports it) over the time scale. Actual start and finish: the job's ``writing`` and
``done`` publications. Errors are (predicted - actual) / actual, both counted from the snapshot.
The phases measured on the way (assignment -> writing, done -> the vehicle's next assignment)
are printed in sim seconds, and the writing (``writing`` -> ``done``) against the planned
duration.
"""

from __future__ import annotations

import argparse
import itertools
import math
import os
import statistics
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from show_day import Phases  # noqa: E402  (benchmarks/)
from show_day_report import ARRIVALS_PER_H, day  # noqa: E402

from bus.messages import (  # noqa: E402
    JobState,
    SubmitReply,
    SubmitRequest,
)
from bus.pubsub import subscribe  # noqa: E402
from bus.rpc import (  # noqa: E402
    NoReplyError,
    RemoteError,
    query_one,
)
from bus.session import Session  # noqa: E402
from cli.showrun import ShowRun, Stagehand, derived_show, snapshot, wait_for_jobs  # noqa: E402
from planner.glyphs import text_glyph  # noqa: E402
from planner.pipeline import PlanOptions, plan_strokes  # noqa: E402
from showfile import load_show  # noqa: E402
from showfile.models import Show  # noqa: E402
from vehicles.jobs import job_setup, lay_out  # noqa: E402
from vehicles.quadrotor_brush.kind import board_of  # noqa: E402

SHOW = ROOT / "shows" / "airshow-2014.yaml"
VEHICLES = 4
CORPUS = "ABQRSgkw" + "永光马和我的是人大中国天"
QUICK_CORPUS = "Ag永马"
VERTICAL_SPEED_MPS = 0.5
"""Climb and descent speed limit of the sim's autopilot moves (SimVehicle default)."""
VERTICAL_ACCEL_MPS2 = 0.8
"""Climb and descent acceleration limit of those moves (SimVehicle default)."""
PACES = ("nominal", "limits")
STAGEHAND_TURNAROUND_S = 0.5
"""Wall time in [s] this run's crew (``cli.showrun.Stagehand``: it looks every 0.3 s, then sends
``fresh_sheet``) takes to change a sheet; the show is told so (``policy.sheet_change_s``, in show
seconds), as a show is told its crew's pace: the default 40 s put every ETA of a 16-job queue late
by 60-100 % (the ETAs count a sheet after every character, the Stagehand changed it at once)."""


def quintic_s(distance_m: float, v_max_mps: float, a_max_mps2: float) -> float:
    """Shortest rest-to-rest minimum-jerk quintic over ``distance_m`` within the limits, [s]
    (peak speed ``15/8 d/T``, peak acceleration ``10/sqrt(3) d/T^2``)."""
    if distance_m <= 0.0:
        return 0.0
    return max(
        15.0 / 8.0 * distance_m / v_max_mps,
        math.sqrt(10.0 / math.sqrt(3.0) * distance_m / a_max_mps2),
    )


@dataclass(frozen=True)
class Cycle:
    """One job of one vehicle, phase by phase, [s]."""

    plan: float
    climb: float
    transit: float
    write: float
    back: float
    land: float

    @property
    def total(self) -> float:
        """The whole cycle, [s]."""
        return self.plan + self.climb + self.transit + self.write + self.back + self.land


def cycle(show: Show, vehicle_id: str, char: str, pace: str) -> Cycle:
    """Plan ``char`` on ``vehicle_id``'s board at ``pace`` and time the job's phases."""
    vehicle = show.vehicle(vehicle_id)
    board = show.board(vehicle.board)
    setup = job_setup(show, vehicle_id)
    options: PlanOptions = replace(setup.settings.plan, board=board_of(setup.surface), pace=pace)
    glyph = lay_out(text_glyph(char), setup.writing_area_m, setup.margin_m)
    start = time.perf_counter()
    traj = plan_strokes(glyph.strokes, options)
    plan_s = time.perf_counter() - start
    limits = show.vehicle_limits(vehicle_id)
    cruise_z = board.center_m_enu[2] + show.planning.write_height_m + show.planning.clearance_m
    home = vehicle.home_m_enu
    hover = (home[0], home[1], cruise_z)
    ends = traj.spline.evaluate(traj.spline.knot_times_s()[[0, -1]])
    a_min = min(limits.a_max_mps2)
    vertical = cruise_z - home[2]
    return Cycle(
        plan=plan_s,
        climb=quintic_s(vertical, VERTICAL_SPEED_MPS, VERTICAL_ACCEL_MPS2),
        transit=quintic_s(math.dist(hover, ends[0]), limits.v_max_mps, a_min),
        write=traj.duration_s,
        back=quintic_s(math.dist(ends[1], hover), limits.v_max_mps, a_min),
        land=quintic_s(vertical, VERTICAL_SPEED_MPS, VERTICAL_ACCEL_MPS2),
    )


def per_hour(cycles: list[Cycle]) -> float:
    """Characters per hour of ``VEHICLES`` vehicles flying these cycles one after another."""
    return VEHICLES * 3600.0 / statistics.mean(c.total for c in cycles)


class JobTimeline:
    """When each job was first seen in each state (orchestrator Unix time [s]), from ``jobs/*``."""

    def __init__(self) -> None:
        self.first: dict[tuple[str, str], float] = {}
        self.last: dict[str, JobState] = {}
        self._lock = threading.Lock()

    def on_job(self, _key: str, job: JobState) -> None:
        with self._lock:
            self.first.setdefault((job.job_id, job.state), job.updated_at_s)
            self.last[job.job_id] = job


def wait_ready(run: ShowRun, session: Session, vehicles: int, timeout_s: float) -> None:
    """Wait until ``vehicles`` vehicles are alive and idle or landed (raises TimeoutError)."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            snap = snapshot(session, run.keys, timeout_s=2.0)
        except (NoReplyError, RemoteError):  # the orchestrator is starting
            time.sleep(0.5)
            continue
        ready = [v for v in snap.vehicles if v.alive and v.state in ("idle", "landed")]
        if len(ready) == vehicles:
            return
        time.sleep(0.5)
    raise TimeoutError(f"vehicles not ready after {timeout_s:.0f} s")


def submit_char(session: Session, run: ShowRun, char: str, index: int) -> SubmitReply:
    """Submit with an idempotency key, retrying while the orchestrator is slow to answer."""
    request = SubmitRequest(text=char, client_id="bench", idempotency_key=f"eta-{index}")
    for _ in range(20):
        try:
            reply = query_one(session, run.keys.submit, request, SubmitReply, timeout_s=10.0)
        except (NoReplyError, RemoteError):
            continue
        if not reply.ok:
            raise RuntimeError(f"{char!r} refused: {reply.error}")
        return reply
    raise TimeoutError(f"{char!r}: no answer to 20 submissions")


def _spread(name: str, errors: list[float]) -> str:
    ordered = sorted(errors)
    p10 = ordered[int(0.1 * (len(ordered) - 1))]
    p90 = ordered[round(0.9 * (len(ordered) - 1))]
    within = sum(1 for e in errors if abs(e) <= 0.2)
    return (
        f"  {name:6} error: median {statistics.median(errors):+6.1%}, p10 {p10:+6.1%},"
        f" p90 {p90:+6.1%}, worst {max(errors, key=abs):+6.1%};"
        f" {within}/{len(errors)} within +-20 %"
    )


def eta_run(chars: str, scale: float, settle_s: float) -> None:
    """Run the show, predict every queued job's start and finish, compare with what happened."""
    timeline = JobTimeline()
    load = os.getloadavg()
    with tempfile.TemporaryDirectory() as tmp:
        base = load_show(SHOW)
        crew = {"sheet_change_s": STAGEHAND_TURNAROUND_S * scale}
        path, show = derived_show(
            SHOW, Path(tmp), time_scale=scale, policy=base.policy.model_copy(update=crew)
        )
        with (
            ShowRun(path, show, log_dir=Path(tmp) / "logs") as run,
            run.client() as session,
            Stagehand(session, run.keys),  # a fresh sheet where a requeued job left ink
        ):
            _sub = subscribe(session, run.keys.jobs_all, JobState, timeline.on_job)
            wait_ready(run, session, len(show.vehicles), timeout_s=120.0)
            replies = [submit_char(session, run, char, k) for k, char in enumerate(chars)]
            time.sleep(settle_s)
            snap = snapshot(session, run.keys)
            ids = [str(r.job_id) for r in replies]
            final = wait_for_jobs(session, run.keys, ids, timeout_s=60.0 + 200.0 * len(chars))
            time.sleep(0.5)  # the last publications
    t0 = snap.time_s
    predicted = {j.job_id: t0 + j.eta_s for j in snap.jobs if j.eta_s is not None}
    print(
        f"ETAs: {len(chars)} characters at time_scale {scale:g}, {len(predicted)} queued at the"
        f" snapshot ({settle_s:g} s after submission); load (1 min) {load[0]:.1f} at the start,"
        f" {os.getloadavg()[0]:.1f} at the end; seconds after the snapshot:"
    )
    print("  job  char vehicle   start: predicted actual  error   finish: predicted actual  error")
    start_err, finish_err = [], []
    for job in final:
        begun = timeline.first.get((job.job_id, "writing"))
        done = timeline.first.get((job.job_id, "done"))
        if job.job_id not in predicted or begun is None or done is None:
            continue
        p_start = predicted[job.job_id] - t0
        p_finish = p_start + (job.planned_duration_s or 0.0) / scale
        a_start, a_finish = begun - t0, done - t0
        start_err.append((p_start - a_start) / a_start)
        finish_err.append((p_finish - a_finish) / a_finish)
        print(
            f"  {job.job_id[-4:]}  {job.label:4} {job.vehicle_id or '-':8}"
            f" {p_start:16.1f} {a_start:6.1f} {start_err[-1]:+6.1%}"
            f" {p_finish:17.1f} {a_finish:6.1f} {finish_err[-1]:+6.1%}"
        )
    if start_err:
        print(_spread("start", start_err))
        print(_spread("finish", finish_err))
    _phases(timeline, final, scale)


def _phases(timeline: JobTimeline, final: list[JobState], scale: float) -> None:
    """Sim seconds from assignment to writing, and from done to the vehicle's next assignment."""
    approach = [
        (timeline.first[(j.job_id, "writing")] - timeline.first[(j.job_id, "assigned")]) * scale
        for j in final
        if (j.job_id, "writing") in timeline.first and (j.job_id, "assigned") in timeline.first
    ]
    turns: dict[str, list[tuple[float, float]]] = {}
    for j in final:
        key_a, key_d = (j.job_id, "assigned"), (j.job_id, "done")
        if j.vehicle_id and key_a in timeline.first and key_d in timeline.first:
            turns.setdefault(j.vehicle_id, []).append(
                (timeline.first[key_a], timeline.first[key_d])
            )
    after = []
    for jobs in turns.values():
        jobs.sort()
        after += [(b[0] - a[1]) * scale for a, b in itertools.pairwise(jobs)]
    stretch = [
        (timeline.first[(j.job_id, "done")] - timeline.first[(j.job_id, "writing")])
        * scale
        / j.planned_duration_s
        for j in final
        if (j.job_id, "writing") in timeline.first
        and (j.job_id, "done") in timeline.first
        and j.planned_duration_s
    ]
    if approach and after and stretch:
        print(
            f"  measured (sim s): assignment -> writing median {statistics.median(approach):.1f};"
            f" done -> next assignment median {statistics.median(after):.1f};"
            f" writing -> done / planned duration median {statistics.median(stretch):.2f}"
        )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="4 characters")
    parser.add_argument("--vehicle", default="uav1", help="vehicle whose board is used")
    parser.add_argument("--eta", action="store_true", help="also run the show and check ETAs")
    parser.add_argument("--eta-only", action="store_true", help="only the ETA run")
    parser.add_argument("--eta-scale", type=float, default=1.0, help="time_scale of that run (1)")
    parser.add_argument("--settle", type=float, default=5.0, help="seconds before the snapshot")
    parser.add_argument("--day", action="store_true", help="a show day, batteries and sheets")
    parser.add_argument("--day-hours", type=float, default=8.0, help="show hours of the day (8)")
    parser.add_argument("--arrivals", type=float, default=ARRIVALS_PER_H,
                        help=f"visitors per hour (assumed: {ARRIVALS_PER_H:g})")  # fmt: skip
    args = parser.parse_args()
    chars = QUICK_CORPUS if args.quick else CORPUS
    if not args.eta_only:
        cycles = throughput(chars, args.vehicle)
        if args.day:
            phases = {c: day_phases(k) for c, k in zip(chars, cycles, strict=True)}
            day(load_show(SHOW), phases, args.day_hours, args.arrivals)
    if args.eta or args.eta_only:
        eta_run(chars, args.eta_scale, args.settle)
    return 0


def day_phases(c: Cycle) -> Phases:
    """A job's phases in the show day (:mod:`show_day`)."""
    return Phases(plan_s=c.plan, to_write_s=c.climb + c.transit, write_s=c.write,
                  back_s=c.back + c.land)  # fmt: skip


def throughput(chars: str, vehicle_id: str) -> list[Cycle]:
    """Plan every character at both paces and print the cycles and characters per hour; the
    cycles at the default pace."""
    show = load_show(SHOW)
    plan_strokes(text_glyph("A").strokes, PlanOptions())  # warm-up: imports, caches
    cycles: dict[str, list[Cycle]] = {pace: [] for pace in PACES}
    print(f"show throughput: {SHOW.name}, {len(chars)} characters on {vehicle_id}'s board")
    print(
        "  char   writing [s]: nominal  limits   cycle [s]: nominal  limits  (climb+transit+"
        "back+land)"
    )
    for char in chars:
        old, new = (cycle(show, vehicle_id, char, pace) for pace in PACES)
        cycles["nominal"].append(old)
        cycles["limits"].append(new)
        other = new.climb + new.transit + new.back + new.land
        print(
            f"  {char}     {old.write:19.1f} {new.write:7.1f} {old.total:18.1f} {new.total:7.1f}"
            f"  ({other:.1f})"
        )
    for pace, label in (("nominal", "today (nominal pace)"), ("limits", "new default (limits)")):
        group = cycles[pace]
        print(
            f"  {label:<22} writing median {statistics.median(c.write for c in group):5.1f} s,"
            f" cycle mean {statistics.mean(c.total for c in group):5.1f} s ->"
            f" {per_hour(group):5.0f} characters per hour with {VEHICLES} vehicles"
        )
    gain = per_hour(cycles["limits"]) / per_hour(cycles["nominal"])
    print(f"  throughput x{gain:.2f}; take-off, transit, return and landing are the same in both")
    return cycles["limits"]


if __name__ == "__main__":
    raise SystemExit(main())

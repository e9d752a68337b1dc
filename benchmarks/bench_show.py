"""Show throughput: characters per hour of the Airshow show, today's default pace beside the new.

    python benchmarks/bench_show.py            # 20 characters (8 Latin, 12 Chinese)
    python benchmarks/bench_show.py --quick    # 4 characters (smoke run)

Each character is laid out and planned as a vehicle agent of ``shows/airshow-2014.yaml`` does it
(``showfile.planning``: the show's board, writing area, margin, limits and planning settings),
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
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from planner.glyphs import text_glyph  # noqa: E402
from planner.pipeline import PlanOptions, plan_strokes  # noqa: E402
from showfile import load_show  # noqa: E402
from showfile.models import Show  # noqa: E402
from showfile.planning import fit_to_board, vehicle_plan_options  # noqa: E402

SHOW = ROOT / "shows" / "airshow-2014.yaml"
VEHICLES = 4
CORPUS = "ABQRSgkw" + "永光马和我的是人大中国天"
QUICK_CORPUS = "Ag永马"
VERTICAL_SPEED_MPS = 0.5
"""Climb and descent speed limit of the sim's autopilot moves (SimVehicle default)."""
VERTICAL_ACCEL_MPS2 = 0.8
"""Climb and descent acceleration limit of those moves (SimVehicle default)."""
PACES = ("nominal", "limits")


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
    options: PlanOptions = replace(vehicle_plan_options(show, vehicle_id), pace=pace)
    glyph = fit_to_board(text_glyph(char), board, show.planning)
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


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="4 characters")
    parser.add_argument("--vehicle", default="uav1", help="vehicle whose board is used")
    args = parser.parse_args()
    show = load_show(SHOW)
    chars = QUICK_CORPUS if args.quick else CORPUS
    plan_strokes(text_glyph("A").strokes, PlanOptions())  # warm-up: imports, caches
    cycles: dict[str, list[Cycle]] = {pace: [] for pace in PACES}
    print(f"show throughput: {SHOW.name}, {len(chars)} characters on {args.vehicle}'s board")
    print(
        "  char   writing [s]: nominal  limits   cycle [s]: nominal  limits  (climb+transit+"
        "back+land)"
    )
    for char in chars:
        old, new = (cycle(show, args.vehicle, char, pace) for pace in PACES)
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
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

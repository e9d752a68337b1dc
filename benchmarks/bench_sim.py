"""Simulated writing quality and simulator speed on one core.

    python benchmarks/bench_sim.py            # the planner corpus: Latin A-Z a-z + 120 Chinese
    python benchmarks/bench_sim.py --quick    # a handful of characters (smoke run)

Quality: every character of the planner corpus (``bench_planner.py``) is laid out 1 m tall,
planned with the default limits and flown with a 2 cm nominal stroke in 1 m/s wind (steady plus
Dryden-like gusts, a random heading per character) with mocap noise and latency on, once with
the paper's published controller and once with the shipped default. Printed: median (and 90th
percentile) pen-down RMSE of the writing point and ink IoU. Vehicles fly in batches (one
vehicle per character), which is also how fast a batch evaluation runs.

Speed: 4 and 100 vehicles writing a 20 s figure at 100 Hz control with 4 physics substeps,
whole closed loop (mocap, filter, controller, physics, log): simulated seconds per wall second
and the cost of one vehicle-tick in microseconds (best of a few runs).
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"
if hasattr(os, "sched_setaffinity"):
    os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import numpy as np  # noqa: E402
from bench_planner import COMMON_HANZI, LATIN  # noqa: E402

from planner.errors import PlannerError  # noqa: E402
from planner.glyphs import has_glyph, text_glyph  # noqa: E402
from planner.samples import TrajectorySamples  # noqa: E402
from sim.params import WindParams  # noqa: E402
from sim.reference import writing_reference  # noqa: E402
from vehicles.jobs import plan_glyph  # noqa: E402
from vehicles.quadrotor_brush import KIND_NAME  # noqa: E402
from vehicles.quadrotor_brush.control.config import DEFAULT_CONFIG, PAPER_CONFIG  # noqa: E402
from vehicles.quadrotor_brush.flight import fly  # noqa: E402
from vehicles.quadrotor_brush.flight_config import FlightConfig  # noqa: E402
from vehicles.quadrotor_brush.metrics import flight_metrics  # noqa: E402
from vehicles.quadrotor_brush.params import WorldParams  # noqa: E402
from vehicles.quadrotor_brush.trace import flown_of  # noqa: E402
from vehicles.registry import vehicle_kind  # noqa: E402
from vehicles.surface import Surface  # noqa: E402

BATCH = 40
WIND_MPS = 1.0


def corpus(quick: bool) -> list[str]:
    if quick:
        return list("AgQ永和我")
    return list(LATIN) + [c for c in COMMON_HANZI if has_glyph(c)][:120]


def plan_corpus(chars: list[str]) -> tuple[dict[str, TrajectorySamples], list[str], list[str]]:
    """Plan every character 1 m tall as ``skyquill fly`` does (the one job-planning function, a
    show file's default settings); one the planner rejects for straying from its strokes is
    planned again without that check (the flight is judged against the plan, not the strokes)."""
    kind = vehicle_kind(KIND_NAME)
    settings = kind.settings(None, None)
    loose_settings = dataclasses.replace(
        settings, plan=dataclasses.replace(settings.plan, fit_tolerance_m=None)
    )
    surface = Surface.of("horizontal", (0.0, 0.0, 0.0), 0.0)
    planned: dict[str, TrajectorySamples] = {}
    failed: list[str] = []
    loose: list[str] = []
    for char in chars:
        glyph = text_glyph(char)
        try:
            job = plan_glyph(kind, settings, surface, glyph, (100.0, 1.0), 0.0)
        except PlannerError as exc:
            try:
                job = plan_glyph(kind, loose_settings, surface, glyph, (100.0, 1.0), 0.0)
            except PlannerError:
                failed.append(f"{char}: {exc}")
                continue
            loose.append(f"{char}: {exc}")
        planned[char] = job.plan.samples
    return planned, failed, loose


def fly_corpus(
    planned: dict[str, TrajectorySamples], config: FlightConfig, seed: int, wind_mps: float
) -> list[tuple[str, float, float]]:
    """(char, pen-down RMSE, IoU) per character; batches of similar durations."""
    order = sorted(planned, key=lambda c: planned[c].duration_s)
    scores = []
    for start in range(0, len(order), BATCH):
        chars = order[start : start + BATCH]
        # one wind heading per batch (a batch is one world), varied between batches
        heading = 2.0 * math.pi * ((seed * 7919 + start * 97) % 360) / 360.0
        world = dataclasses.replace(
            config.world, wind=WindParams.from_speed(wind_mps, heading_rad=heading)
        )
        log = fly([planned[c] for c in chars], dataclasses.replace(config, world=world), seed=seed)
        for i, char in enumerate(chars):
            m = flight_metrics(flown_of(log, i), world.brush, planned[char])
            scores.append((char, m.rmse_pen_down_m, m.iou))
    return scores


def summarise(name: str, scores: list[tuple[str, float, float]]) -> dict[str, float]:
    rmse = [s[1] for s in scores]
    iou = [s[2] for s in scores]
    summary = {
        "median_rmse_pen_down_m": statistics.median(rmse),
        "p90_rmse_pen_down_m": float(np.percentile(rmse, 90)),
        "median_iou": statistics.median(iou),
        "p10_iou": float(np.percentile(iou, 10)),
        "n": len(scores),
    }
    worst = max(scores, key=lambda s: s[1])
    print(
        f"  {name:<13} pen-down RMSE median {summary['median_rmse_pen_down_m'] * 1000:6.2f} mm"
        f" (p90 {summary['p90_rmse_pen_down_m'] * 1000:6.2f})   IoU median"
        f" {summary['median_iou']:.3f} (p10 {summary['p10_iou']:.3f})   n={len(scores)}"
        f"   worst {worst[0]} {worst[1] * 1000:.1f} mm"
    )
    return summary


def speed(n_vehicles: int, repeats: int) -> dict[str, float]:
    r = writing_reference(shape="figure8", size_m=0.6, writing_time_s=18.0)
    ref = TrajectorySamples(
        r.t_s, r.position_m_enu, r.velocity_mps_enu, r.acceleration_mps2_enu, r.pen_down
    )
    config = FlightConfig(world=WorldParams(wind=WindParams.from_speed(WIND_MPS)), preroll_s=0.0)
    best = math.inf
    ticks = 0
    sim_s = 0.0
    for _ in range(repeats):
        start = time.perf_counter()
        log = fly([ref] * n_vehicles, config, seed=1)
        best = min(best, time.perf_counter() - start)
        ticks = log.t_s.shape[0]
        sim_s = ticks * config.world.dt_s
    return {
        "vehicles": n_vehicles,
        "real_time_factor": sim_s / best,
        "us_per_vehicle_tick": best / (ticks * n_vehicles) * 1e6,
        "us_per_tick": best / ticks * 1e6,
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a handful of characters")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--calm", action="store_true", help="also fly both without wind")
    parser.add_argument("--json", metavar="FILE", help="also write the numbers here")
    args = parser.parse_args()

    world = WorldParams()
    chars = corpus(args.quick)
    start = time.perf_counter()
    planned, failed, loose = plan_corpus(chars)
    print(
        f"corpus: {len(chars)} characters, {len(planned)} planned in"
        f" {time.perf_counter() - start:.1f} s; {len(loose)} only without the planner's"
        f" stroke-fit check, {len(failed)} not at all"
    )
    for line in (failed + loose)[:5]:
        print(f"  planner: {line}")
    print(
        f"quality: 1 m tall, 2 cm stroke, {WIND_MPS} m/s wind (steady + gusts), mocap noise"
        " 0.2 mm, latency 5 ms"
    )
    results: dict[str, object] = {
        "planned": len(planned),
        "planner_failures": failed,
        "planned_without_fit_check": loose,
    }
    runs = [("paper", PAPER_CONFIG, WIND_MPS), ("default", DEFAULT_CONFIG, WIND_MPS)]
    if args.calm:
        runs += [("paper", PAPER_CONFIG, 0.0), ("default", DEFAULT_CONFIG, 0.0)]
    for name, controller, wind in runs:
        start = time.perf_counter()
        config = FlightConfig(world=world, controller=controller)
        scores = fly_corpus(planned, config, args.seed, wind)
        key = name if wind == WIND_MPS else f"{name}_calm"
        results[key] = summarise(key, scores)
        results[key]["wall_s"] = time.perf_counter() - start  # type: ignore[index]
    print("  targets (wind): median RMSE <= 10 mm, median IoU >= 0.8")
    print("  anchors: Flying Calligrapher (real hexarotor) 29 mm end-effector RMSE, IoU 0.59")

    print("speed: one core, 100 Hz control, 4 physics substeps, full closed loop with logging")
    for n, repeats in ((4, 3), (100, 2)):
        s = speed(n, repeats)
        results[f"speed_{n}"] = s
        print(
            f"  {n:>3} vehicles: {s['real_time_factor']:7.1f}x real time,"
            f" {s['us_per_tick']:7.0f} us per tick, {s['us_per_vehicle_tick']:6.1f} us per"
            " vehicle-tick"
        )
    print("  targets: 4 vehicles >= 50x, 100 vehicles >= 1x real time")
    print("  anchor: Crazyswarm2's simulator, 16 drones at 0.6x real time")
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=2) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

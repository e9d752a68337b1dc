"""The ground writer (Chugo et al.): standard against proposed wheel control, writing, speed.

    nice -n 15 python benchmarks/bench_ground.py [--quick] [--png PATH]

In one run, in MuJoCo:

1. The paper's 0.1 m step (section 3.1): slip ratio (eq. 19) and rotation error ratio (eq. 20),
   mean |ratio| per wheel group during the climb, standard against proposed, beside the paper's
   Table 2 (Working Model 2D). Run with Table 1's roller friction (0.3) and with rubber rollers
   (1.0); neither method climbs 0.1 m in the model (higher than the 66 mm wheel radius, a wheel
   must be lifted by friction on the riser), so the rubber run is repeated on a 60 mm step.
2. Highest step climbed (rubber rollers), by bisection to 5 mm per method, beside the paper's
   prototype (72 mm standard, 152 mm proposed).
3. Writing a 2 m character (永) on the floor: pen-down RMSE and IoU against the targets
   (<= 5 mm, >= 0.85).
4. Real-time factor (simulated over wall and over CPU seconds) for one and four ground writers
   with their controllers, beside the bare MuJoCo step of the same model (the peer).

``--quick``: one climb per method, no sweep, 一 1 m, shorter speed runs. A PNG with the climb's
slips over time, the sweep and the written character is saved (``--png``).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import matplotlib

matplotlib.use("Agg")

import mujoco
import numpy as np
from matplotlib.figure import Figure

from planner.glyphs.layout import fit_to_area
from planner.glyphs.text import text_glyph
from vehicles.kind import FlownWriting, StrokeInput, WritingPlan, WritingScore
from vehicles.omni_wheel.climb import (
    METHODS,
    TABLE_1,
    ClimbResult,
    Method,
    climb,
    configuration_of,
)
from vehicles.omni_wheel.floor_plan import DEFAULT_SETTINGS, RUBBER_ROLLERS, plan_floor
from vehicles.omni_wheel.sim import OmniWorld
from vehicles.omni_wheel.terrain import Terrain
from vehicles.omni_wheel.wheel_control import proposed_references
from vehicles.omni_wheel.writing import drive_plan, score_floor
from vehicles.surface import Surface

PAPER_TABLE_2 = {
    "standard": {"slip": (31.3, 30.3, 29.6, 30.3), "rot": (16.5, 16.3, 16.6, 16.5)},
    "proposed": {"slip": (13.1, 14.3, 14.2, 13.9), "rot": (7.4, 7.2, 7.9, 7.5)},
}
PAPER_HIGHEST_M = {"standard": 0.072, "proposed": 0.152}
CLIMBED_STEP_M = 0.06
"""A step in [m] both methods climb in the model (about the wheel radius, 66 mm)."""


def _pct(values: dict[str, float]) -> str:
    return "  ".join(f"{100.0 * values[k]:5.1f}" for k in ("front", "middle", "rear", "average"))


def step_table(
    label: str, geometry_friction: float, height_m: float = 0.1
) -> dict[Method, ClimbResult]:
    """Section 1 for one roller friction and step height."""
    geometry = TABLE_1 if geometry_friction == TABLE_1.friction_static else RUBBER_ROLLERS
    print(f"\n{height_m} m step, roller friction {geometry.friction_static} ({label})")
    print("                         front middle  rear   avg  climbed   time")
    out: dict[Method, ClimbResult] = {}
    for method in METHODS:
        r = climb(method, height_m, geometry=geometry, time_limit_s=10.0)
        out[method] = r
        tail = f"  {r.climbed!s:5s}  {r.duration_s:5.1f} s"
        print(f"  {method:8s} slip [%]   {_pct(r.by_group(r.slip_per_wheel))}{tail}")
        print(f"  {method:8s} rot. [%]   {_pct(r.by_group(r.rotation_error_per_wheel))}")
    for method in METHODS:
        p = PAPER_TABLE_2[method]
        print(f"  paper {method:8s} slip {p['slip']}  rot {p['rot']}")
    return out


def highest_step_m(method: Method, lo: float = 0.0, hi: float = 0.30, tol: float = 0.005) -> float:
    """Highest step (bisection, ``tol`` [m]) climbed with rubber rollers."""
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        if climb(method, mid, geometry=RUBBER_ROLLERS, time_limit_s=12.0).climbed:
            lo = mid
        else:
            hi = mid
    return lo


Written = tuple[WritingPlan, FlownWriting, WritingScore, float]
"""Plan, driven run, score and CPU seconds of one written character."""


def write(text: str, size_m: float) -> Written:
    """Plan, drive and score ``text`` ``size_m`` tall on the floor; returns the CPU seconds too."""
    glyph = fit_to_area(text_glyph(text), width_m=size_m, height_m=size_m)
    strokes = [StrokeInput(np.asarray(s, dtype=np.float64)) for s in glyph.strokes]
    surface = Surface.of("floor", (3.0, 1.0, 0.0), 0.0)
    plan = plan_floor(strokes, surface, DEFAULT_SETTINGS)
    cpu = time.process_time()
    flown = drive_plan(plan, DEFAULT_SETTINGS, seed=0)
    cpu = time.process_time() - cpu
    return plan, flown, score_floor(plan, flown, DEFAULT_SETTINGS.marker_width_m), cpu


def real_time_factor(
    n_vehicles: int, seconds: float, *, shared: bool
) -> tuple[float, float, float]:
    """(wall RTF, CPU RTF) of ``n_vehicles`` writers with their controllers, and the wall RTF of
    the bare MuJoCo steps of the same model(s) (no Python control). ``shared``: all in one MuJoCo
    model; else one world each (as the vehicle agents run them, one per vehicle)."""
    v = np.array([0.15, 0.05, 0.0])
    if shared:
        starts = tuple((0.0, 2.0 * k, 0.0, 0.0) for k in range(n_vehicles))
        worlds = [(OmniWorld(RUBBER_ROLLERS, Terrain(), starts, seed=0), n_vehicles)]
    else:
        worlds = [
            (OmniWorld(RUBBER_ROLLERS, Terrain(), ((0.0, 0.0, 0.0, 0.0),), seed=k), 1)
            for k in range(n_vehicles)
        ]
    wall, cpu = time.perf_counter(), time.process_time()
    while worlds[0][0].t_s < seconds:
        for world, n in worlds:
            refs = [
                proposed_references(v, configuration_of(world.sense(k)), RUBBER_ROLLERS).rate_radps
                for k in range(n)
            ]
            world.step(np.stack(refs))
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    bare = time.perf_counter()
    for world, _ in worlds:
        for _ in range(int(seconds / world.model.opt.timestep)):
            mujoco.mj_step(world.model, world.data)
    bare = time.perf_counter() - bare
    return seconds / wall, seconds / cpu, seconds / bare


def figure(climbs: dict[Method, ClimbResult], sweep: dict[str, float], written: Written) -> Figure:
    """Slips during the 0.1 m climb, the sweep, and the written character."""
    fig = Figure(figsize=(15, 4.5), layout="constrained")
    ax_slip, ax_sweep, ax_ink = fig.subplots(1, 3)
    for method, style in zip(METHODS, ("--", "-"), strict=True):
        r = climbs[method]
        if r.log["t_s"].size:
            with np.errstate(all="ignore"):
                ax_slip.plot(
                    r.log["t_s"], 100 * np.nanmean(r.log["slip"], axis=1), style, label=method
                )
    ax_slip.set_xlabel("t [s]")
    ax_slip.set_ylabel("mean |slip| of the wheels [%]")
    ax_slip.set_title(f"{CLIMBED_STEP_M} m step, rubber rollers")
    ax_slip.legend()
    names = list(sweep)
    ax_sweep.bar(names, [1e3 * sweep[n] for n in names])
    ax_sweep.set_ylabel("highest step climbed [mm]")
    ax_sweep.set_title("sweep (paper: 72 / 152 mm)")
    plan, flown, score, _ = written
    ref = plan.surface.to_surface(flown.reference_m_enu)
    pt = plan.surface.to_surface(flown.writing_point_m_enu)
    ax_ink.plot(np.where(flown.pen_down, ref[:, 0], np.nan), ref[:, 1], "k", lw=3)
    ax_ink.plot(np.where(flown.ink_width_m > 0, pt[:, 0], np.nan), pt[:, 1], "r", lw=1)
    ax_ink.set_aspect("equal")
    ax_ink.set_title(f"RMSE {1e3 * score.rmse_pen_down_m:.1f} mm, IoU {score.iou:.3f}")
    return fig


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--png", type=Path, default=Path("bench_ground.png"))
    args = parser.parse_args()
    step_table("Table 1", TABLE_1.friction_static)
    step_table("rubber", RUBBER_ROLLERS.friction_static)
    climbs = step_table("rubber", RUBBER_ROLLERS.friction_static, CLIMBED_STEP_M)
    sweep: dict[str, float] = {}
    if not args.quick:
        print("\nhighest step climbed (rubber rollers, bisection to 5 mm)")
        for method in METHODS:
            sweep[method] = highest_step_m(method)
            paper = 1e3 * PAPER_HIGHEST_M[method]
            print(f"  {method:8s} {1e3 * sweep[method]:5.0f} mm   paper {paper:.0f} mm")
    text, size = ("一", 1.0) if args.quick else ("永", 2.0)
    written = write(text, size)
    plan, _, score, cpu = written
    print(f"\nwriting {text} {size:.0f} m on the floor: {plan.duration_s:.1f} s driven")
    rmse_mm = 1e3 * score.rmse_pen_down_m
    print(f"  pen-down RMSE {rmse_mm:.2f} mm (target <= 5), IoU {score.iou:.3f} (target >= 0.85)")
    print(f"  drive CPU {cpu:.1f} s")
    seconds = 2.0 if args.quick else 10.0
    print("\nreal-time factor (writers with controllers | bare MuJoCo step, same model)")
    runs = ((1, False, ""), (4, False, " (a world each)"), (4, True, " (one model)"))
    for n, shared, how in runs:
        wall, cpu_rtf, bare = real_time_factor(n, seconds, shared=shared)
        label = f"{n} writer(s){how}"
        print(f"  {label:28s} {wall:6.2f} x wall, {cpu_rtf:6.2f} x CPU | bare {bare:6.2f} x wall")
    figure(climbs, sweep, written).savefig(args.png, dpi=110)
    print(f"\nfigure: {args.png}")


if __name__ == "__main__":
    main()

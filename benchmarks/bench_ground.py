"""The ground writer (Chugo et al.): standard against proposed wheel control, writing, speed.

    nice -n 15 python benchmarks/bench_ground.py [--quick] [--png PATH]

In one run, in MuJoCo (climb tables: ``ground_climbs.py``):

1. The paper's 0.1 m step (section 3.1) at Table 1's roller friction (0.3): the quasi-static
   bound of each phase (``statics``) and a run per method; neither can climb it.
2. The 0.1 m step with rubber rollers (our analogue of the experiment's vehicle, not the
   simulation's 0.3), both methods over 4 seeds: slip ratio (eq. 19) and rotation error ratio
   (eq. 20), mean |ratio| during the climb, and proposed over standard; Table 2 beside only when
   every run climbed. Once with the model as read (``geometry``), once with the other reading of
   the rear mass centre (midway between the rear part's axles).
3. Highest step climbed per method (rubber), beside the prototype's 72 / 152 mm.
4. Sensitivity: the 0.1 m step and the highest step with one reading changed per row (mass
   centre, motor torque, roller friction, frame clearance).
5. Writing a 2 m character (永) on the floor: pen-down RMSE and IoU against the targets
   (<= 5 mm, >= 0.85).
6. Real-time factor (simulated over wall and over CPU seconds) for one and four ground writers
   with their controllers, beside the bare MuJoCo step of the same model (the peer).

``--quick``: 2 seeds, the model as read only, no highest step or sensitivity, 一 1 m, shorter
speed runs. A PNG with the climb's slips over time, the highest steps and the written character
is saved (``--png``).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import matplotlib

matplotlib.use("Agg")

import mujoco
import numpy as np
from ground_climbs import (
    OTHER_READING,
    PAPER_HIGHEST_M,
    PAPER_STEP_M,
    StepComparison,
    highest_steps,
    paper_friction_bound,
    sensitivity,
    step_over_seeds,
)
from matplotlib.figure import Figure

from planner.glyphs.layout import fit_to_area
from planner.glyphs.text import text_glyph
from vehicles.kind import FlownWriting, StrokeInput, WritingPlan, WritingScore
from vehicles.omni_wheel.climb import METHODS, configuration_of
from vehicles.omni_wheel.floor_plan import DEFAULT_SETTINGS, RUBBER_ROLLERS, plan_floor
from vehicles.omni_wheel.sim import OmniWorld
from vehicles.omni_wheel.terrain import Terrain
from vehicles.omni_wheel.wheel_control import proposed_references
from vehicles.omni_wheel.writing import drive_plan, score_floor
from vehicles.surface import Surface

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


def _score_line(score: WritingScore) -> str:
    """Pen-down RMSE and IoU in words (``not measured`` where the pen never came down)."""
    rmse = (
        "not measured" if score.rmse_pen_down_m is None else f"{1e3 * score.rmse_pen_down_m:.2f} mm"
    )
    iou = "not measured" if score.iou is None else f"{score.iou:.3f}"
    return f"pen-down RMSE {rmse}, IoU {iou}"


def figure(climbs: StepComparison, highest: dict[str, float], written: Written) -> Figure:
    """Slips during the 0.1 m climb (seed 0), the highest steps, and the written character."""
    fig = Figure(figsize=(15, 4.5), layout="constrained")
    ax_slip, ax_high, ax_ink = fig.subplots(1, 3)
    for method, style in zip(METHODS, ("--", "-"), strict=True):
        r = climbs.runs[method].runs[0]
        if r.log["t_s"].size:
            with np.errstate(all="ignore"):
                ax_slip.plot(
                    r.log["t_s"], 100 * np.nanmean(r.log["slip"], axis=1), style,
                    label=f"{method} ({'climbed' if r.climbed else 'stalled'})",
                )  # fmt: skip
    ax_slip.set_xlabel("t [s]")
    ax_slip.set_ylabel("mean |slip| of the wheels [%]")
    ax_slip.set_title(f"{PAPER_STEP_M} m step, rubber rollers, as read")
    ax_slip.legend()
    names = list(highest)
    ax_high.bar(names, [1e3 * highest[n] for n in names])
    for method in METHODS:
        ax_high.axhline(1e3 * PAPER_HIGHEST_M[method], color="0.5", lw=0.8, ls=":")
    ax_high.set_ylabel("highest step climbed [mm]")
    ax_high.set_title("model (bars), prototype 72 / 152 mm (dotted)")
    ax_high.tick_params(axis="x", labelrotation=20, labelsize=7)
    plan, flown, score, _ = written
    ref = plan.surface.to_surface(flown.reference_m_enu)
    pt = plan.surface.to_surface(flown.writing_point_m_enu)
    ax_ink.plot(np.where(flown.pen_down, ref[:, 0], np.nan), ref[:, 1], "k", lw=3)
    ax_ink.plot(np.where(flown.ink_width_m > 0, pt[:, 0], np.nan), pt[:, 1], "r", lw=1)
    ax_ink.set_aspect("equal")
    ax_ink.set_title(_score_line(score))
    return fig


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--png", type=Path, default=Path("bench_ground.png"))
    args = parser.parse_args()
    print(f"load (1-min) at start: {os.getloadavg()[0]:.1f}")
    paper_friction_bound()
    seeds = range(2) if args.quick else range(4)
    climbs = step_over_seeds("rubber rollers, as read", RUBBER_ROLLERS, seeds)
    highest: dict[str, float] = {}
    if not args.quick:
        step_over_seeds("rubber rollers, rear mass centre -0.1075 m", OTHER_READING, seeds)
        for method, h in highest_steps(RUBBER_ROLLERS).items():
            highest[f"{method}, as read"] = h
        for label, row in sensitivity().items():
            if label.startswith("rear mass centre -0.1075"):
                highest.update({f"{m}, com -0.1075": row[m] for m in METHODS})
    text, size = ("一", 1.0) if args.quick else ("永", 2.0)
    written = write(text, size)
    plan, _, score, cpu = written
    print(f"\nwriting {text} {size:.0f} m on the floor: {plan.duration_s:.1f} s driven")
    print(f"  {_score_line(score)} (targets: RMSE <= 5 mm, IoU >= 0.85)")
    print(f"  drive CPU {cpu:.1f} s")
    seconds = 2.0 if args.quick else 10.0
    print("\nreal-time factor (writers with controllers | bare MuJoCo step, same model)")
    runs = ((1, False, ""), (4, False, " (a world each)"), (4, True, " (one model)"))
    for n, shared, how in runs:
        wall, cpu_rtf, bare = real_time_factor(n, seconds, shared=shared)
        label = f"{n} writer(s){how}"
        print(f"  {label:28s} {wall:6.2f} x wall, {cpu_rtf:6.2f} x CPU | bare {bare:6.2f} x wall")
    figure(climbs, highest, written).savefig(args.png, dpi=110)
    print(f"\nfigure: {args.png}")
    print(f"load (1-min) at end: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()

"""``skyquill fly``: plan a character, fly it in the simulator, score and picture the writing.

Exit status: 0 when the writing met its bounds (the defaults of a show file's ``safety`` section:
pen-down RMSE, ink IoU; ``--rmse-max``, ``--iou-min``), 1 when it did not or the flight was
aborted (tracking error above ``--deviation-bound`` for longer than its window), with the reason on
stderr; 2 for bad input."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

from vehicles import DEFAULT_KIND
from vehicles.quadrotor_brush import KIND_NAME as BRUSH_KIND

BRUSH_OPTIONS = {"wind": 0.0, "wind_heading_deg": 0.0, "stroke_width": 0.02, "gains": "default"}
"""Options of the brush quadrotor's world and controller (its wind, brush and gains), with
their defaults."""
NAME = "fly"
HELP = "Plan, fly in the simulator and score a strokes file or text (metrics.json, report.png)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from vehicles import kind_names

    parser.add_argument(
        "--kind",
        choices=kind_names(),
        default=DEFAULT_KIND,
        help=f"vehicle kind ({DEFAULT_KIND}); the options below marked [brush] are "
        f"{BRUSH_KIND}'s own",
    )
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--strokes", metavar="FILE", help="strokes JSON (docs/formats.md)")
    source.add_argument("--text", metavar="TEXT", help="Latin (Hershey) or Chinese text")
    parser.add_argument("--seed", type=int, default=0, help="random seed of wind and mocap (0)")
    parser.add_argument(
        "--wind", type=float, default=0.0, metavar="M_PER_S", help="[brush] mean wind [m/s] (0)"
    )
    parser.add_argument(
        "--wind-heading-deg", type=float, default=0.0, help="[brush] wind towards [deg from east]"
    )
    parser.add_argument("--report", metavar="DIR", help="write metrics.json and report.png here")
    parser.add_argument("--height", type=float, default=1.0, help="character height [m] (1.0)")
    parser.add_argument(
        "--stroke-width", type=float, default=0.02, help="[brush] nominal stroke width [m] (0.02)"
    )
    add_bound_arguments(parser)
    parser.add_argument(
        "--gains",
        choices=("default", "paper"),
        default="default",
        help="[brush] controller: shipped default or the paper's published set",
    )


def add_bound_arguments(parser: argparse.ArgumentParser) -> None:
    """The writing and tracking bounds, defaulting to a show file's ``safety`` section."""
    from showfile.safety import SafetySettings

    d = SafetySettings()
    add = parser.add_argument
    add(
        "--rmse-max",
        type=float,
        default=d.rmse_pen_down_max_m,
        metavar="M",
        help=f"largest pen-down RMSE [m] of a good writing ({d.rmse_pen_down_max_m})",
    )
    add(
        "--iou-min",
        type=float,
        default=d.iou_min,
        metavar="X",
        help=f"smallest ink IoU of a good writing ({d.iou_min})",
    )
    add(
        "--deviation-bound",
        type=float,
        default=d.deviation_bound_m,
        metavar="M",
        help=f"abort when the tracking error stays above this [m] ({d.deviation_bound_m}) ...",
    )
    add("--deviation-window", type=float, default=d.deviation_window_s, metavar="S",
        help=f"... for longer than this [s] ({d.deviation_window_s})")  # fmt: skip


def glyph_of(args: argparse.Namespace) -> Any:
    from planner.glyphs import parse_strokes_json, text_glyph

    if args.text is not None:
        return text_glyph(args.text)
    path = Path(args.strokes)
    return parse_strokes_json(path.read_text(encoding="utf-8"), source_name=path.name)


FLY_INK_PIXEL_M = 0.001
"""Pixel size in [m] of the ink rasters of ``fly``'s IoU (finer than a show's 2 mm: one job)."""


def _settings(args: argparse.Namespace) -> Any:
    """The brush quadrotor's settings of a show file left at its defaults, with this run's
    stroke width, wind, controller and deviation bound."""
    import dataclasses
    import math

    from sim.params import WindParams
    from vehicles.deviation import DeviationLimit
    from vehicles.quadrotor_brush.control.config import PAPER_CONFIG
    from vehicles.registry import vehicle_kind

    base = vehicle_kind(BRUSH_KIND).settings(None, None)
    world = base.flight.world
    world = dataclasses.replace(
        world,
        brush=dataclasses.replace(world.brush, nominal_width_m=args.stroke_width),
        wind=WindParams.from_speed(args.wind, heading_rad=math.radians(args.wind_heading_deg)),
    )
    flight = dataclasses.replace(
        base.flight,
        world=world,
        controller=PAPER_CONFIG if args.gains == "paper" else base.flight.controller,
        deviation=DeviationLimit(args.deviation_bound, args.deviation_window),
    )
    return dataclasses.replace(base, flight=flight, ink_pixel_m=FLY_INK_PIXEL_M)


def run(args: argparse.Namespace) -> int:
    if args.kind != BRUSH_KIND:
        from cli.fly_kind import run_kind
        from showfile.safety import SafetySettings

        d = SafetySettings()
        brush_only = {
            **BRUSH_OPTIONS,
            "deviation_bound": d.deviation_bound_m,
            "deviation_window": d.deviation_window_s,
        }
        return run_kind(args, {k: getattr(args, k) != v for k, v in brush_only.items()})
    from planner.errors import PlannerError
    from vehicles.jobs import plan_glyph
    from vehicles.registry import vehicle_kind
    from vehicles.surface import Surface
    from vehicles.verdict import WritingBounds, writing_verdict

    kind = vehicle_kind(BRUSH_KIND)
    try:
        glyph = glyph_of(args)
        settings = _settings(args)
        surface = Surface.of("horizontal", (0.0, 0.0, 0.0), 0.0)
        area = (100.0 * args.height, args.height)  # the character is --height tall
        job = plan_glyph(kind, settings, surface, glyph, area, 0.0)
    except (PlannerError, OSError, ValueError) as exc:
        print(f"skyquill fly: {exc}", file=sys.stderr)
        return 2
    plan = job.plan
    start = time.perf_counter()
    flown = kind.fly(plan, settings, seed=args.seed)
    wall_s = time.perf_counter() - start
    score = kind.score(plan, flown, settings)
    controller = settings.flight.controller
    bounds = WritingBounds(args.rmse_max, args.iou_min)
    iou = score.iou if score.iou is not None else float("nan")
    problem = flown.abort_reason or writing_verdict(score.rmse_pen_down_m, iou, bounds)
    sim_time_s = score.extra["sim_time_s"]
    doc: dict[str, Any] = {
        "rmse_pen_down_m": score.rmse_pen_down_m,
        "rmse_m": score.rmse_m,
        "max_error_m": score.max_error_m,
        "iou": iou,
        **score.extra,
        "wall_time_s": wall_s,
        "real_time_factor": sim_time_s / wall_s if wall_s > 0 else None,
        "seed": args.seed,
        "wind_mps": args.wind,
        "wind_heading_deg": args.wind_heading_deg,
        "gains": controller.gains.to_json_dict(),
        "disturbance_compensation": controller.disturbance_compensation,
        "brush_lever_m": controller.brush_lever_m,
        "character_height_m": args.height,
        "nominal_width_m": settings.flight.world.brush.nominal_width_m,
        "label": glyph.label,
        "planned_duration_s": plan.duration_s,
        "aborted": flown.abort_reason,
        "within_bounds": problem is None,
        "bounds": {"rmse_pen_down_max_m": args.rmse_max, "iou_min": args.iou_min,
                   "deviation_bound_m": args.deviation_bound,
                   "deviation_window_s": args.deviation_window},
    }  # fmt: skip
    print(json.dumps({k: doc[k] for k in ("rmse_pen_down_m", "rmse_m", "max_error_m", "iou",
                                           "sim_time_s", "wall_time_s")}))  # fmt: skip
    if args.report:
        _write_report(args, kind, job, flown, settings, doc)
    if problem is not None:
        print(f"skyquill fly: writing out of bounds: {problem}", file=sys.stderr)
        return 1
    return 0


def _write_report(
    args: argparse.Namespace, kind: Any, job: Any, flown: Any, settings: Any, doc: dict[str, Any]
) -> None:
    """``metrics.json`` and ``report.png`` into ``--report``."""
    from vehicles.picture import save_png

    out = Path(args.report)
    out.mkdir(parents=True, exist_ok=True)
    (out / "metrics.json").write_text(json.dumps(doc, indent=2) + "\n", encoding="utf-8")
    gains = settings.flight.controller.gains.name
    title = f"{job.glyph.label!r}: gains {gains}, wind {args.wind} m/s, seed {args.seed}"
    save_png(kind.report(job.plan, flown, settings, title), out / "report.png")

"""``skyquill fly``: plan a character, fly it in the simulator, score and picture the writing.

The character is laid out as ``skyquill plan`` lays it (:mod:`cli.writing_args`: inside
``--width`` x ``--height`` less ``--margin``), so both commands plan the same thing. Prints a
human summary (``--json``: the metrics document, one line); an aborted flight, or one that wrote
nothing, says so and scores 0 (:mod:`cli.flight_outcome`).

Exit status: 0 when the writing met its bounds (the defaults of a show file's ``safety`` section:
pen-down RMSE, ink IoU; ``--rmse-max``, ``--iou-min``), 1 when it did not or the flight was
aborted (tracking error above ``--deviation-bound`` for longer than its window), with the reason on
stderr; 2 for bad input."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

from cli.writing_args import (
    POSITIVE_M,
    add_area_arguments,
    add_source_arguments,
    area_of,
    bounded,
    print_error,
    read_glyph,
    source_of,
)
from vehicles import DEFAULT_KIND
from vehicles.quadrotor_brush import KIND_NAME as BRUSH_KIND

BRUSH_OPTIONS = {"wind": 0.0, "wind_heading_deg": 0.0, "stroke_width": 0.02, "gains": "default"}
"""Options of the brush quadrotor's world and controller (its wind, brush and gains), with
their defaults."""
NAME = "fly"
HELP = "Plan, fly in the simulator and score a strokes file or text (metrics.json, report.png)."
PROG = "skyquill fly"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from vehicles import kind_names

    parser.add_argument(
        "--kind",
        choices=kind_names(),
        default=DEFAULT_KIND,
        help=f"vehicle kind ({DEFAULT_KIND}); the options below marked [brush] are "
        f"{BRUSH_KIND}'s own",
    )
    add_source_arguments(parser)
    parser.add_argument(
        "--seed", type=int, default=0, help="random seed of wind and mocap (0; 0 or more)"
    )
    parser.add_argument(
        "--wind",
        type=bounded(0.0, unit="m/s"),
        default=0.0,
        metavar="M_PER_S",
        help="[brush] mean wind [m/s] (0; at most what the vehicle can hold against at its "
        "tilt limit, about 15 m/s)",
    )
    parser.add_argument(
        "--wind-heading-deg",
        type=bounded(-360.0, 360.0, unit="deg"),
        default=0.0,
        help="[brush] wind towards [deg from east]",
    )
    parser.add_argument("--report", metavar="DIR", help="write metrics.json and report.png here")
    parser.add_argument("--json", action="store_true", help="print the metrics as one JSON line")
    parser.add_argument(
        "--stroke-width",
        type=POSITIVE_M,
        default=0.02,
        help="[brush] nominal stroke width [m] (0.02)",
    )
    add_area_arguments(parser)
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
        type=POSITIVE_M,
        default=d.rmse_pen_down_max_m,
        metavar="M",
        help=f"largest pen-down RMSE [m] of a good writing ({d.rmse_pen_down_max_m})",
    )
    add(
        "--iou-min",
        type=bounded(0.0, 1.0),
        default=d.iou_min,
        metavar="X",
        help=f"smallest ink IoU of a good writing, 0 to 1 ({d.iou_min})",
    )
    add(
        "--deviation-bound",
        type=POSITIVE_M,
        default=d.deviation_bound_m,
        metavar="M",
        help=f"abort when the tracking error stays above this [m] ({d.deviation_bound_m}) ...",
    )
    add("--deviation-window", type=bounded(0.0, unit="s", open_low=True),
        default=d.deviation_window_s, metavar="S",
        help=f"... for longer than this [s] ({d.deviation_window_s})")  # fmt: skip


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
    check_wind(args.wind, world.quadrotor)
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


def check_wind(wind_mps: float, quadrotor: Any) -> None:
    """ValueError naming ``--wind`` above the steady wind the vehicle can hold its position
    against: its drag ``c v`` equal to the horizontal thrust ``m g tan(tilt)`` at the inner loop's
    tilt limit (``QuadrotorParams``: 1 kg, 0.5 rad, 0.35 N/(m/s): 15.3 m/s). Above it the flight
    can only be blown away; below it a strong wind may still abort, and says so."""
    import math

    q = quadrotor
    drag = max(q.drag_n_per_mps[0], q.drag_n_per_mps[1])
    most = q.mass_kg * q.gravity_mps2 * math.tan(q.max_tilt_rad) / drag if drag > 0 else math.inf
    if wind_mps > most:
        raise ValueError(
            f"--wind {wind_mps:g} m/s: above {most:.1f} m/s, the steady wind the vehicle can hold "
            f"against at its {q.max_tilt_rad:g} rad tilt limit (drag {drag:g} N per m/s)"
        )


def run(args: argparse.Namespace) -> int:
    if args.seed < 0:
        print(f"{PROG}: error: --seed must be 0 or more, not {args.seed}", file=sys.stderr)
        return 2
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
    from cli.flight_outcome import flight_doc, print_outcome
    from planner.errors import PlannerError
    from vehicles.jobs import plan_glyph
    from vehicles.registry import vehicle_kind
    from vehicles.surface import Surface

    kind = vehicle_kind(BRUSH_KIND)
    try:
        settings = _settings(args)
    except ValueError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    try:
        glyph = read_glyph(args)
        surface = Surface.of("horizontal", (0.0, 0.0, 0.0), 0.0)
        job = plan_glyph(kind, settings, surface, glyph, area_of(args), args.margin)
    except (PlannerError, ValueError) as exc:
        return print_error(PROG, source_of(args), exc)
    plan = job.plan
    start = time.perf_counter()
    flown = kind.fly(plan, settings, seed=args.seed)
    wall_s = time.perf_counter() - start
    score = kind.score(plan, flown, settings)
    controller = settings.flight.controller
    doc = flight_doc(args, job.glyph, plan, flown, score, wall_s)
    doc.update(
        wind_mps=args.wind,
        wind_heading_deg=args.wind_heading_deg,
        gains=controller.gains.to_json_dict(),
        disturbance_compensation=controller.disturbance_compensation,
        brush_lever_m=controller.brush_lever_m,
        nominal_width_m=settings.flight.world.brush.nominal_width_m,
    )
    doc["bounds"].update(
        deviation_bound_m=args.deviation_bound, deviation_window_s=args.deviation_window
    )
    if args.report:
        _write_report(args, kind, job, flown, settings, doc)
    return print_outcome(args, doc)


def _write_report(
    args: argparse.Namespace, kind: Any, job: Any, flown: Any, settings: Any, doc: dict[str, Any]
) -> None:
    """``metrics.json`` and ``report.png`` into ``--report``."""
    from cli.flight_outcome import metrics_text
    from vehicles.picture import save_png

    out = Path(args.report)
    out.mkdir(parents=True, exist_ok=True)
    (out / "metrics.json").write_text(metrics_text(doc), encoding="utf-8")
    gains = settings.flight.controller.gains.name
    title = f"{job.glyph.label}: gains {gains}, wind {args.wind:g} m/s, seed {args.seed}"
    save_png(kind.report(job.plan, flown, settings, title), out / "report.png")

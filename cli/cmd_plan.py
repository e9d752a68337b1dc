"""``skyquill plan``: strokes file or text -> checked minimum-jerk trajectory (TRAJ.json, plot)."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

NAME = "plan"
HELP = "Plan a flyable minimum-jerk writing trajectory for a strokes file or text."

_PROG = "skyquill plan"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--strokes", metavar="FILE", help="strokes JSON (docs/formats.md)")
    source.add_argument("--text", metavar="TEXT", help="Latin (Hershey) or Chinese text")
    parser.add_argument("--out", metavar="TRAJ.json", help="write the trajectory here")
    parser.add_argument("--plot", metavar="PLOT.png", help="write a figure of the plan here")
    board = parser.add_argument_group("writing area (board-local metres)")
    board.add_argument("--width", type=float, default=1.0, help="area width [m] (1.0)")
    board.add_argument("--height", type=float, default=1.0, help="area height [m] (1.0)")
    board.add_argument("--margin", type=float, default=0.05, help="margin inside the area [m]")
    board.add_argument(
        "--board-center",
        type=float,
        nargs=3,
        metavar=("E", "N", "U"),
        default=(0.0, 0.0, 0.0),
        help="board surface centre, world ENU [m]",
    )
    board.add_argument("--board-yaw-deg", type=float, default=0.0, help="board yaw [deg]")
    board.add_argument(
        "--write-height",
        type=float,
        default=0.30,
        help="reference height above the board while writing [m] (0.30)",
    )
    board.add_argument(
        "--clearance", type=float, default=0.08, help="extra height with the pen up [m] (0.08)"
    )
    lim = parser.add_argument_group("vehicle limits")
    lim.add_argument(
        "--a-max",
        type=float,
        nargs="+",
        metavar="A",
        help="max |acceleration| [m/s^2]: one value, or x y z (0.8 0.8 0.5)",
    )
    lim.add_argument("--v-max", type=float, default=0.5, help="max speed [m/s] (0.5)")
    lim.add_argument("--mass", type=float, default=1.0, help="vehicle mass [kg] (1.0)")
    lim.add_argument("--thrust-max", type=float, help="max thrust [N] (2 x weight)")
    lim.add_argument(
        "--body-rate-max",
        type=float,
        default=3.0,
        help="max body-rate bound of eq. 15 [rad/s] (3.0)",
    )
    opt = parser.add_argument_group("planner")
    opt.add_argument("--total-time", type=float, help="fixed total time [s] (default: free)")
    opt.add_argument("--solver", choices=("piqp", "clarabel", "osqp"), default="piqp")
    opt.add_argument("--method", choices=("qp", "closed-form"), default="qp")
    opt.add_argument("--no-resegment", action="store_true", help="keep the initial times")
    opt.add_argument("--resegment-method", choices=("analytic", "numerical"), default="analytic")
    opt.add_argument(
        "--split-threshold", type=float, default=0.01, help="split-and-merge threshold [m] (0.01)"
    )
    opt.add_argument("--rate", type=float, default=100.0, help="sample rate of TRAJ.json [Hz]")


def _error(source: str, exc: Exception) -> int:
    from planner.errors import PlannerError

    where = [source]
    message = str(exc)
    if isinstance(exc, PlannerError):
        message = exc.message.removeprefix(f"{source}: ")
        if exc.stroke_index is not None:
            where.append(f"stroke {exc.stroke_index}")
        if exc.point_index is not None:
            where.append(f"point {exc.point_index}")
        if exc.stroke_index is None and exc.field is not None:
            where.append(f"field {exc.field!r}")
    location = ", ".join(where[1:])
    prefix = f"{source}: {location}" if location else source
    print(f"{_PROG}: error: {prefix}: {message}", file=sys.stderr)
    return 2


def _options(args: argparse.Namespace) -> Any:
    from planner.board import BoardFrame
    from planner.limits import GRAVITY_MPS2, VehicleLimits
    from planner.pipeline import PlanOptions

    a_max = args.a_max or [0.8, 0.8, 0.5]
    if len(a_max) == 1:
        a_max = a_max * 3
    if len(a_max) != 3:
        raise ValueError("--a-max takes one value or three (x y z)")
    thrust = args.thrust_max if args.thrust_max is not None else 2.0 * args.mass * GRAVITY_MPS2
    limits = VehicleLimits(
        a_max_mps2=(a_max[0], a_max[1], a_max[2]),
        v_max_mps=args.v_max,
        mass_kg=args.mass,
        thrust_max_n=thrust,
        body_rate_max_radps=args.body_rate_max,
    )
    return PlanOptions(
        limits=limits,
        board=BoardFrame(tuple(args.board_center), math.radians(args.board_yaw_deg)),
        write_height_m=args.write_height,
        clearance_m=args.clearance,
        total_time_s=args.total_time,
        split_threshold_m=args.split_threshold,
        resegment=not args.no_resegment,
        resegment_method=args.resegment_method,
        solver=args.solver,
        method=args.method,
        sample_rate_hz=args.rate,
    )


def run(args: argparse.Namespace) -> int:
    from planner.errors import PlannerError
    from planner.glyphs import fit_to_area, parse_strokes_json, text_glyph
    from planner.pipeline import plan_strokes

    source = args.strokes if args.strokes is not None else "<text>"
    try:
        if args.strokes is not None:
            try:
                text = Path(args.strokes).read_text(encoding="utf-8")
            except (OSError, UnicodeDecodeError) as exc:
                return _error(source, ValueError(f"cannot read: {exc}"))
            glyph = parse_strokes_json(text, source_name=args.strokes)
        else:
            glyph = text_glyph(args.text)
        if glyph.units != "m":
            glyph = fit_to_area(
                glyph, width_m=args.width, height_m=args.height, margin_m=args.margin
            )
        options = _options(args)
        traj = plan_strokes(glyph.strokes, options)
    except (PlannerError, ValueError) as exc:
        return _error(source, exc)
    if args.out:
        Path(args.out).write_text(json.dumps(traj.to_json_dict(args.rate)), encoding="utf-8")
    if args.plot:
        from planner.plots import plot_trajectory

        plot_trajectory(traj, glyph.strokes).savefig(args.plot, dpi=100)
    _summary(traj)
    return 0


def _summary(traj: Any) -> None:
    f = traj.feasibility
    acc = ", ".join(f"{a:.2f}" for a in f.peak_accel_mps2)
    print(f"duration {traj.duration_s:.2f} s, {len(traj.turning_points_board_m)} strokes")
    print(
        f"peak |a| x,y,z {acc} m/s^2; peak speed {f.peak_speed_mps:.2f} m/s;"
        f" thrust {f.min_thrust_n:.1f}..{f.peak_thrust_n:.1f} N;"
        f" body-rate bound {f.body_rate_bound_radps:.2f} rad/s"
    )
    print(
        f"fit error at turning points: max {f.fit_error_max_m * 1e3:.1f} mm,"
        f" rms {f.fit_error_rms_m * 1e3:.1f} mm; pen-down path within"
        f" {f.path_error_max_m * 1e3:.1f} mm of the strokes"
    )
    print("timing ms: " + ", ".join(f"{k} {v:.1f}" for k, v in traj.timing_ms.items()))

"""``skyquill plan``: strokes file or text -> checked minimum-jerk trajectory (TRAJ.json, plot).

``--kind`` plans for another vehicle kind through its room (:mod:`cli.plan_kind`); the options
marked [brush] are the brush quadrotor's own and refused for another kind. The brush quadrotor
plans as its kind plans (:mod:`vehicles.quadrotor_brush.planning`), without building the
settings of its flight (world, controller), which a plan does not read. The character is laid
out as ``skyquill fly`` lays it (:mod:`cli.writing_args`). Prints a human summary with the
verdict ``feasible: yes/no`` (:mod:`cli.summary`); ``--json`` the same facts as one JSON line."""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from cli.writing_args import (
    add_area_arguments,
    add_source_arguments,
    area_of,
    cannot_write,
    ink_size_m,
    print_error,
    read_glyph,
    source_of,
)
from planner import defaults
from planner.limits import VehicleLimits
from vehicles import DEFAULT_KIND
from vehicles.quadrotor_brush import KIND_NAME as BRUSH_KIND

if TYPE_CHECKING:
    from planner.options import PlanOptions

NAME = "plan"
HELP = "Plan a flyable minimum-jerk writing trajectory for a strokes file or text."

PROG = "skyquill plan"


class _BrushOption(argparse.Action):
    """An option of the brush quadrotor only: stored as ``store`` does (``nargs=0``: as
    ``store_const``), and its flag added to ``args.brush_options_given``, so that another kind
    refuses it even when its value is the default (which ``--help`` shows and the brush reads)."""

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: str | Sequence[Any] | None,
        option_string: str | None = None,
    ) -> None:
        setattr(namespace, self.dest, self.const if self.nargs == 0 else values)
        namespace.brush_options_given = (*namespace.brush_options_given, option_string)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The kind, the input and output files, then the writing area, vehicle limits and planner
    groups (in this order in ``--help``)."""
    from vehicles import kind_names

    parser.add_argument(
        "--kind",
        choices=kind_names(),
        default=DEFAULT_KIND,
        help=f"vehicle kind ({DEFAULT_KIND}); the options marked [brush] are {BRUSH_KIND}'s own",
    )
    parser.set_defaults(brush_options_given=())
    add_source_arguments(parser)
    parser.add_argument("--json", action="store_true", help="print the summary as one JSON line")
    parser.add_argument(
        "--out", metavar="TRAJ.json", help="write the trajectory here (another kind: PLAN.json)"
    )
    parser.add_argument(
        "--plot", metavar="PLOT.png", help=f"write a figure of the plan here ({BRUSH_KIND})"
    )
    _add_board_arguments(parser)
    _add_limit_arguments(parser)
    _add_planner_arguments(parser)


def _add_board_arguments(parser: argparse.ArgumentParser) -> None:
    """Where on which board the text is laid out, and the heights the brush flies at."""
    add_area_arguments(parser)
    board = parser.add_argument_group("board")
    board.add_argument(
        "--board-center",
        type=float,
        nargs=3,
        metavar=("E", "N", "U"),
        help="board surface centre, world ENU [m] (0 0 0; a wall's centre 1.5 m up)",
    )
    board.add_argument("--board-yaw-deg", type=float, default=0.0, help="board yaw [deg]")
    board.add_argument(
        "--write-height",
        type=float,
        default=defaults.WRITE_HEIGHT_M,
        action=_BrushOption,
        help="[brush] reference height above the board while writing [m]"
        f" ({defaults.WRITE_HEIGHT_M})",
    )
    board.add_argument(
        "--clearance",
        type=float,
        default=defaults.CLEARANCE_M,
        action=_BrushOption,
        help=f"[brush] extra height with the pen up [m] ({defaults.CLEARANCE_M})",
    )


def _add_limit_arguments(parser: argparse.ArgumentParser) -> None:
    """The vehicle's limits, each defaulting to a show file's default (:class:`VehicleLimits`)."""
    d = VehicleLimits()
    lim = parser.add_argument_group("vehicle limits [brush] (a show file's defaults)")
    lim.add_argument(
        "--a-max",
        type=float,
        nargs="+",
        metavar="A",
        action=_BrushOption,
        help="max |acceleration| [m/s^2]: one value, or x y z"
        f" ({' '.join(str(a) for a in d.a_max_mps2)})",
    )
    lim.add_argument(
        "--v-max",
        type=float,
        default=d.v_max_mps,
        action=_BrushOption,
        help=f"max speed [m/s] ({d.v_max_mps})",
    )
    lim.add_argument(
        "--mass",
        type=float,
        default=d.mass_kg,
        action=_BrushOption,
        help=f"vehicle mass [kg] ({d.mass_kg})",
    )
    lim.add_argument(
        "--thrust-max", type=float, action=_BrushOption, help="max thrust [N] (2 x weight)"
    )
    lim.add_argument(
        "--body-rate-max",
        type=float,
        default=d.body_rate_max_radps,
        action=_BrushOption,
        help=f"max body-rate bound of eq. 15 [rad/s] ({d.body_rate_max_radps})",
    )


def _add_planner_arguments(parser: argparse.ArgumentParser) -> None:
    """The trajectory planner's options: total time, QP solver, method, re-segmentation, split
    threshold and the sample rate of the written trajectory."""
    opt = parser.add_argument_group("planner [brush]")
    opt.add_argument(
        "--total-time", type=float, action=_BrushOption, help="fixed total time [s] (default: free)"
    )
    opt.add_argument(
        "--solver",
        choices=defaults.SOLVERS,
        default=defaults.SOLVERS[0],
        action=_BrushOption,
        help=f"QP solver of the acceleration-limited fit ({defaults.SOLVERS[0]})",
    )
    opt.add_argument(
        "--method",
        choices=("qp", "closed-form"),
        default="qp",
        action=_BrushOption,
        help="qp: the limits imposed; closed-form: only checked (qp)",
    )
    opt.add_argument(
        "--no-resegment",
        nargs=0,
        const=True,
        default=False,
        action=_BrushOption,
        help="keep the initial times",
    )
    opt.add_argument(
        "--resegment-method",
        choices=("analytic", "numerical"),
        default="analytic",
        action=_BrushOption,
        help="re-segmentation gradient: analytic (envelope, L-BFGS) or numerical "
        "(the paper's eq. 56) (analytic)",
    )
    opt.add_argument(
        "--split-threshold",
        type=float,
        default=defaults.SPLIT_THRESHOLD_M,
        action=_BrushOption,
        help=f"split-and-merge threshold [m] ({defaults.SPLIT_THRESHOLD_M})",
    )
    opt.add_argument(
        "--rate",
        type=float,
        default=defaults.SAMPLE_RATE_HZ,
        action=_BrushOption,
        help=f"sample rate of TRAJ.json [Hz] ({defaults.SAMPLE_RATE_HZ:g})",
    )


def _plan_options(args: argparse.Namespace) -> PlanOptions:
    """The brush quadrotor's planner options with this run's limits and options, the others
    those of a show file left at its defaults (``PlanOptions()``, as the kind's settings have
    them without a show)."""
    from planner.limits import GRAVITY_MPS2
    from planner.options import PlanOptions

    a_max = args.a_max or list(VehicleLimits().a_max_mps2)
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
        write_height_m=args.write_height,
        clearance_m=args.clearance,
        total_time_s=args.total_time,
        split_threshold_m=args.split_threshold,
        resegment=not args.no_resegment,
        resegment_method=args.resegment_method,
        solver=args.solver,
        dense_qp_budget_s=defaults.ONE_OFF_DENSE_QP_BUDGET_S,
        method=args.method,
        sample_rate_hz=args.rate,
    )


def _one_blas_thread() -> None:
    """Ask OpenBLAS for one thread, before numpy loads it (no effect once loaded; a value set in
    the environment wins). A plan's matrices (a few hundred rows) gain nothing from a second
    thread, while starting it and its spin-waits cost this one-off command 0.07 s of wall and
    0.28 s of CPU (median of 7 at load 2.3 on 2 cores); plans are the same (tests)."""
    if "numpy" not in sys.modules:
        os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def run(args: argparse.Namespace) -> int:
    _one_blas_thread()
    if args.kind != BRUSH_KIND:
        from cli.plan_kind import run_kind

        return run_kind(args)
    from planner.errors import PlannerError
    from planner.glyphs import fit_to_area
    from vehicles.quadrotor_brush.planning import plan_on_surface
    from vehicles.surface import Surface

    source = source_of(args)
    try:
        width_m, height_m = area_of(args)
        glyph = fit_to_area(
            read_glyph(args), width_m=width_m, height_m=height_m, margin_m=args.margin
        )
        centre = tuple(args.board_center or (0.0, 0.0, 0.0))
        surface = Surface.of("horizontal", centre, math.radians(args.board_yaw_deg))
        traj = plan_on_surface(glyph.strokes, surface, _plan_options(args))
    except (PlannerError, ValueError) as exc:
        return print_error(PROG, source, exc)
    try:
        if args.out:
            Path(args.out).write_text(json.dumps(traj.to_json_dict(args.rate)), encoding="utf-8")
        if args.plot:
            from planner.plots import plot_trajectory

            plot_trajectory(traj, glyph.strokes).savefig(args.plot, dpi=100)
    except OSError as exc:
        return cannot_write(PROG, exc)
    if args.json:
        print(json.dumps(_summary_json(glyph, traj), ensure_ascii=False))
    else:
        print("\n".join(summary_lines(glyph, traj)))
    return 0


def _summary_json(glyph: Any, traj: Any) -> dict[str, Any]:
    """What ``--json`` prints: the summary's facts (the trajectory itself: ``--out``)."""
    f = traj.feasibility
    return {
        "label": glyph.label,
        "kind": BRUSH_KIND,
        "ink_size_m": ink_size_m(glyph),
        "duration_s": traj.duration_s,
        "strokes": len(traj.turning_points_board_m),
        "feasible": f.feasible,
        "violations": [str(v) for v in f.violations()],
        "feasibility": f.to_json_dict(),
        "timing_ms": dict(traj.timing_ms),
    }


def summary_lines(glyph: Any, traj: Any) -> list[str]:
    """The human summary of a brush quadrotor plan (:mod:`cli.summary`'s voice)."""
    from cli.summary import length, numbers, plan_headline, sig

    f = traj.feasibility
    strokes = len(traj.turning_points_board_m)
    size_m = ink_size_m(glyph)
    lines = [plan_headline(glyph.label, BRUSH_KIND, size_m, traj.duration_s, strokes, f.feasible)]
    lines.extend(f"  {violation}" for violation in f.violations())
    lines.append(
        f"  peak acceleration x, y, z {numbers(f.peak_accel_mps2)} of"
        f" {numbers(f.accel_upper_mps2)} m/s^2; peak speed {sig(f.peak_speed_mps)} of"
        f" {sig(f.v_max_mps)} m/s"
    )
    lines.append(
        f"  thrust {sig(f.min_thrust_n)} to {sig(f.peak_thrust_n)} of {sig(f.thrust_max_n)} N;"
        f" body-rate bound {sig(f.body_rate_bound_radps)} of {sig(f.body_rate_max_radps)} rad/s"
    )
    lines.append(
        f"  fit error at turning points: max {length(f.fit_error_max_m)},"
        f" rms {length(f.fit_error_rms_m)}; pen-down path within {length(f.path_error_max_m)}"
        " of the strokes"
    )
    timing = traj.timing_ms
    parts = ", ".join(f"{k} {sig(v, 2)}" for k, v in timing.items() if k != "total")
    lines.append(f"  planned in {sig(timing.get('total'), 2)} ms ({parts})")
    return lines

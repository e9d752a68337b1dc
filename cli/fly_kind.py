"""``skyquill fly --kind K`` for the kinds other than the brush quadrotor: plan, fly in the kind's
simulated world, score and picture the writing, through the kind's interface only
(``vehicles/kind.py``), so a new room flies here without a change to this file.

Exit status as ``skyquill fly``: 0 within the writing bounds, 1 outside them or aborted, 2 for
bad input (including a brush quadrotor option given to another kind).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

WALL_CENTRE_HEIGHT_M = 1.5
"""Height in [m] of the writing area's centre on a wall (the floor and boards: their surface)."""


def run_kind(args: argparse.Namespace, brush_options_set: dict[str, bool]) -> int:
    """Plan, fly, score and report ``args.kind``; ``brush_options_set`` names the brush
    quadrotor's own options and whether each was given."""
    from cli.cmd_fly import glyph_of
    from planner.errors import PlannerError
    from vehicles.jobs import plan_glyph
    from vehicles.quadrotor_brush import KIND_NAME as BRUSH_KIND
    from vehicles.registry import vehicle_kind
    from vehicles.surface import Surface
    from vehicles.verdict import WritingBounds, writing_verdict

    given = [name for name, is_set in brush_options_set.items() if is_set]
    if given:
        flag = "--" + given[0].replace("_", "-")
        print(f"skyquill fly: {flag} is an option of {BRUSH_KIND}, not of {args.kind}",
              file=sys.stderr)  # fmt: skip
        return 2
    kind = vehicle_kind(args.kind)
    try:
        glyph = glyph_of(args)
        settings = kind.settings(None, None)
        centre_z_m = WALL_CENTRE_HEIGHT_M if kind.orientation == "vertical" else 0.0
        surface = Surface.of(kind.orientation, (0.0, 0.0, centre_z_m), 0.0)
        area = (100.0 * args.height, args.height)  # the character is --height tall
        job = plan_glyph(kind, settings, surface, glyph, area, 0.0)
    except (PlannerError, OSError, ValueError) as exc:
        print(f"skyquill fly: {exc}", file=sys.stderr)
        return 2
    start = time.perf_counter()
    flown = kind.fly(job.plan, settings, seed=args.seed)
    wall_s = time.perf_counter() - start
    score = kind.score(job.plan, flown, settings)
    iou = score.iou if score.iou is not None else float("nan")
    bounds = WritingBounds(args.rmse_max, args.iou_min)
    problem = flown.abort_reason or writing_verdict(score.rmse_pen_down_m, iou, bounds)
    sim_time_s = float(flown.t_s[-1] - flown.t_s[0]) if flown.t_s.size else 0.0
    doc: dict[str, Any] = {
        "kind": args.kind,
        "rmse_pen_down_m": score.rmse_pen_down_m,
        "rmse_m": score.rmse_m,
        "max_error_m": score.max_error_m,
        "iou": iou,
        **score.extra,
        "sim_time_s": sim_time_s,
        "wall_time_s": wall_s,
        "real_time_factor": sim_time_s / wall_s if wall_s > 0 else None,
        "seed": args.seed,
        "character_height_m": args.height,
        "label": glyph.label,
        "planned_duration_s": job.plan.duration_s,
        "feasibility": dict(job.plan.feasibility),
        "aborted": flown.abort_reason,
        "within_bounds": problem is None,
        "bounds": {"rmse_pen_down_max_m": args.rmse_max, "iou_min": args.iou_min},
    }
    summary = ("rmse_pen_down_m", "rmse_m", "max_error_m", "iou", "sim_time_s", "wall_time_s")
    print(json.dumps({k: doc[k] for k in summary}))
    if args.report:
        from vehicles.picture import save_png

        out = Path(args.report)
        out.mkdir(parents=True, exist_ok=True)
        text = json.dumps(doc, indent=2, default=str) + "\n"
        (out / "metrics.json").write_text(text, encoding="utf-8")
        title = f"{glyph.label!r} by {args.kind}, seed {args.seed}"
        save_png(kind.report(job.plan, flown, settings, title), out / "report.png")
    if problem is not None:
        print(f"skyquill fly: writing out of bounds: {problem}", file=sys.stderr)
        return 1
    return 0

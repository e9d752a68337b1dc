"""``skyquill fly --kind K`` for the kinds other than the brush quadrotor: plan, fly in the kind's
simulated world, score and picture the writing, through the kind's interface only
(``vehicles/kind.py``), so a new room flies here without a change to this file.

Exit status as ``skyquill fly``: 0 within the writing bounds, 1 outside them or aborted, 2 for
bad input (including a brush quadrotor option given to another kind).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path


def run_kind(args: argparse.Namespace, brush_options_set: dict[str, bool]) -> int:
    """Plan, fly, score and report ``args.kind``; ``brush_options_set`` names the brush
    quadrotor's own options and whether each was given."""
    from cli.flight_outcome import flight_doc, metrics_text, print_outcome
    from cli.writing_args import WALL_CENTRE_HEIGHT_M, area_of, print_error, read_glyph, source_of
    from planner.errors import PlannerError
    from vehicles.jobs import plan_glyph
    from vehicles.quadrotor_brush import KIND_NAME as BRUSH_KIND
    from vehicles.registry import vehicle_kind
    from vehicles.surface import Surface

    given = [name for name, is_set in brush_options_set.items() if is_set]
    if given:
        flag = "--" + given[0].replace("_", "-")
        print(f"skyquill fly: {flag} is an option of {BRUSH_KIND}, not of {args.kind}",
              file=sys.stderr)  # fmt: skip
        return 2
    kind = vehicle_kind(args.kind)
    try:
        glyph = read_glyph(args)
        settings = kind.settings(None, None)
        centre_z_m = WALL_CENTRE_HEIGHT_M if kind.orientation == "vertical" else 0.0
        surface = Surface.of(kind.orientation, (0.0, 0.0, centre_z_m), 0.0)
        job = plan_glyph(kind, settings, surface, glyph, area_of(args), args.margin)
    except (PlannerError, ValueError) as exc:
        return print_error("skyquill fly", source_of(args), exc)
    start = time.perf_counter()
    flown = kind.fly(job.plan, settings, seed=args.seed)
    wall_s = time.perf_counter() - start
    score = kind.score(job.plan, flown, settings)
    doc = flight_doc(args, job.glyph, job.plan, flown, score, wall_s)
    doc["feasibility"] = dict(job.plan.feasibility)
    if args.report:
        from vehicles.picture import save_png

        out = Path(args.report)
        out.mkdir(parents=True, exist_ok=True)
        (out / "metrics.json").write_text(metrics_text(doc), encoding="utf-8")
        title = f"{glyph.label} by {args.kind}, seed {args.seed}"
        save_png(kind.report(job.plan, flown, settings, title), out / "report.png")
    return print_outcome(args, doc)

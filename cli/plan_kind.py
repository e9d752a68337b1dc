"""``skyquill plan --kind K`` for the kinds other than the brush quadrotor: lay the glyph out on
the kind's surface and plan it through the kind's interface only (``vehicles/kind.py``), so a new
room plans here without a change to this file.

Writes ``PLAN.json`` (docs/formats.md) and prints the summary every plan prints (the character,
duration, strokes, ``feasible: yes/no``, each peak against its limit; ``--json``: those and the
kind's whole feasibility report, one line). Exit status 0, or 2 for bad input: a plan the kind
cannot make, a brush quadrotor option, or ``--plot`` (a kind draws a figure of a flown job only:
``skyquill fly``).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from vehicles.kind import WritingPlan

PROG = "skyquill plan"
PLAN_FORMAT = "skyquill.plan/1"
"""``format`` of ``PLAN.json``; a reader refuses a major version it does not know."""


def run_kind(args: argparse.Namespace) -> int:
    """Plan ``args.kind`` and report it (``args`` as ``skyquill plan`` parses them)."""
    from cli.writing_args import (
        WALL_CENTRE_HEIGHT_M,
        area_of,
        cannot_write,
        print_error,
        read_glyph,
        source_of,
    )
    from planner.errors import PlannerError
    from vehicles.jobs import plan_glyph
    from vehicles.quadrotor_brush import KIND_NAME as BRUSH_KIND
    from vehicles.registry import vehicle_kind
    from vehicles.surface import Surface

    if args.brush_options_given:
        flag = args.brush_options_given[0]
        return _refuse(f"{flag} is an option of {BRUSH_KIND}, not of {args.kind}")
    if args.plot:
        return _refuse(
            f"--plot draws {BRUSH_KIND} plans only; a figure of {args.kind} needs a flight:"
            f" skyquill fly --kind {args.kind} --report DIR"
        )
    kind = vehicle_kind(args.kind)
    source = source_of(args)
    try:
        glyph = read_glyph(args)
        settings = kind.settings(None, None)
        centre_z_m = WALL_CENTRE_HEIGHT_M if kind.orientation == "vertical" else 0.0
        centre = tuple(args.board_center or (0.0, 0.0, centre_z_m))
        surface = Surface.of(kind.orientation, centre, math.radians(args.board_yaw_deg))
        job = plan_glyph(kind, settings, surface, glyph, area_of(args), args.margin)
    except (PlannerError, ValueError) as exc:
        return print_error(PROG, source, exc)
    if args.out:
        doc = plan_json_dict(kind.name, job.plan)
        try:
            Path(args.out).write_text(json.dumps(doc, default=_plain), encoding="utf-8")
        except OSError as exc:
            return cannot_write(PROG, exc)
    if args.json:
        print(json.dumps(summary_json(job.glyph, kind.name, job.plan), default=_plain,
                         ensure_ascii=False))  # fmt: skip
    else:
        print("\n".join(summary_lines(job.glyph, kind.name, job.plan)))
    return 0


def _refuse(message: str) -> int:
    print(f"{PROG}: {message}", file=sys.stderr)
    return 2


def summary_json(glyph: Any, kind_name: str, plan: WritingPlan) -> dict[str, Any]:
    """What ``--json`` prints of a kind's plan of ``glyph`` (as laid out)."""
    from cli.summary import feasible
    from cli.writing_args import ink_size_m

    return {
        "label": glyph.label,
        "kind": kind_name,
        "ink_size_m": ink_size_m(glyph),
        "duration_s": plan.duration_s,
        "strokes": len(plan.strokes),
        "feasible": feasible(plan.feasibility),
        "feasibility": dict(plan.feasibility),
    }


def summary_lines(glyph: Any, kind_name: str, plan: WritingPlan) -> list[str]:
    """The human summary of a kind's plan of ``glyph``: the headline and each peak against its
    limit."""
    from cli.summary import feasible, limits_line, plan_headline
    from cli.writing_args import ink_size_m

    report = plan.feasibility
    ok = feasible(report)
    size_m = ink_size_m(glyph)
    head = plan_headline(glyph.label, kind_name, size_m, plan.duration_s, len(plan.strokes), ok)
    limits = limits_line(report)
    return [head, f"  peak {limits}"] if limits else [head]


def plan_json_dict(kind_name: str, plan: WritingPlan) -> dict[str, Any]:
    """Content of ``PLAN.json`` of a :class:`vehicles.kind.WritingPlan` (see docs/formats.md)."""
    import numpy as np

    samples = plan.samples.to_json_dict()
    for name in ("force_n", "width_m"):
        values = getattr(plan, name)
        if values is not None:
            samples[name] = np.round(values, 6).tolist()
    surface = plan.surface
    return {
        "format": PLAN_FORMAT,
        "kind": kind_name,
        "duration_s": round(plan.duration_s, 6),
        "samples": samples,
        "surface": {
            "orientation": surface.orientation,
            "origin_m_enu": list(surface.origin_m_enu),
            "x_axis_enu": list(surface.x_axis_enu),
            "y_axis_enu": list(surface.y_axis_enu),
        },
        "feasibility": dict(plan.feasibility),
    }


def _plain(value: Any) -> Any:
    """A numpy scalar or array as JSON (``json.dumps``'s ``default``)."""
    if hasattr(value, "tolist"):
        return value.tolist()
    raise TypeError(f"not JSON: {type(value).__name__}")

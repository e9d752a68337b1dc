"""``skyquill plan --kind K`` for the kinds other than the brush quadrotor: lay the glyph out on
the kind's surface and plan it through the kind's interface only (``vehicles/kind.py``), so a new
room plans here without a change to this file.

Writes ``PLAN.json`` (docs/formats.md) and prints the duration, the stroke count and the plan's
own feasibility report. Exit status 0, or 2 for bad input: a plan the kind cannot make, a brush
quadrotor option, or ``--plot`` (a kind draws a figure of a flown job only: ``skyquill fly``).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from vehicles.kind import WritingPlan

PLAN_FORMAT = "skyquill.plan/1"
"""``format`` of ``PLAN.json``; a reader refuses a major version it does not know."""


def run_kind(args: argparse.Namespace) -> int:
    """Plan ``args.kind`` and report it (``args`` as ``skyquill plan`` parses them)."""
    from cli.cmd_plan import cannot_write, print_error, read_glyph, source_of
    from cli.fly_kind import WALL_CENTRE_HEIGHT_M
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
        job = plan_glyph(kind, settings, surface, glyph, (args.width, args.height), args.margin)
    except (PlannerError, ValueError) as exc:
        return print_error(source, exc)
    if args.out:
        doc = plan_json_dict(kind.name, job.plan)
        try:
            Path(args.out).write_text(json.dumps(doc, default=_plain), encoding="utf-8")
        except OSError as exc:
            return cannot_write(exc)
    print(f"{kind.name}: duration {job.plan.duration_s:.2f} s, {len(job.plan.strokes)} strokes")
    for line in feasibility_lines(job.plan.feasibility):
        print(line)
    return 0


def _refuse(message: str) -> int:
    print(f"skyquill plan: {message}", file=sys.stderr)
    return 2


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


def feasibility_lines(feasibility: Mapping[str, Any]) -> list[str]:
    """``key: value`` lines of a plan's feasibility report, floats to four significant digits;
    a list of mappings (the sponge's periods) one indented line per item."""
    lines = []
    for key, value in feasibility.items():
        if isinstance(value, list | tuple) and value and all(isinstance(v, Mapping) for v in value):
            lines.append(f"{key}:")
            lines.extend(f"  - {_shown(item)}" for item in value)
        else:
            lines.append(f"{key}: {_shown(value)}")
    return lines


def _shown(value: Any) -> str:
    if isinstance(value, float):
        return repr(float(f"{value:.4g}"))
    if isinstance(value, Mapping):
        return ", ".join(f"{k}: {_shown(v)}" for k, v in value.items())
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_shown(v) for v in value) + "]"
    return str(value)

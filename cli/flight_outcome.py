"""What ``skyquill fly`` reports of a flight, for every kind: only what was measured.

A flight that was aborted, or that laid no ink, scores an ink IoU of 0 and says so (IoU of
nothing against a target is 0: ``sim.ink.iou``); a pen-down RMSE of a flight whose pen never came
down is ``None`` (not measured), never 0. The document is ``metrics.json`` and what ``--json``
prints; the human summary is made of it (:func:`cli.summary.flight_lines`).
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from cli.writing_args import ink_size_m
from vehicles.kind import FlownWriting, WritingPlan, WritingScore
from vehicles.verdict import WritingBounds, writing_verdict


@dataclass(frozen=True)
class Measured:
    """The figures a flight may claim."""

    rmse_pen_down_m: float | None
    """Pen-down RMSE in [m]; None when the pen never came down (not measured)."""
    iou: float
    """Ink IoU; 0 for an aborted flight or one that laid no ink."""
    wrote_ink: bool
    """Whether any ink reached the surface."""


def measured(score: WritingScore, flown: FlownWriting) -> Measured:
    """The figures of ``score`` that ``flown`` supports (the module's rule)."""
    wrote = bool((flown.ink_width_m > 0.0).any())
    counted = wrote and flown.abort_reason is None and score.iou is not None
    pen_down = bool(flown.pen_down.any())
    return Measured(
        rmse_pen_down_m=score.rmse_pen_down_m if pen_down else None,
        iou=float(score.iou) if counted and score.iou is not None else 0.0,
        wrote_ink=wrote,
    )


def measured_extra(extra: Mapping[str, Any], figures: Measured) -> dict[str, Any]:
    """The kind's own figures (``WritingScore.extra``) that were measured: none of the pen-down
    part of a flight whose pen never came down (names with ``pen_down``), none of ink that is
    not counted (names starting ``ink_``)."""
    kept = {}
    for name, value in extra.items():
        if figures.rmse_pen_down_m is None and "pen_down" in name:
            continue
        if figures.iou == 0.0 and name.startswith("ink_"):
            continue
        kept[name] = value
    return kept


def verdict(flown: FlownWriting, figures: Measured, bounds: WritingBounds) -> str | None:
    """Why the flight failed its bounds (None: it met them)."""
    if flown.abort_reason is not None:
        return flown.abort_reason
    if not figures.wrote_ink:
        return "nothing written"
    rmse = figures.rmse_pen_down_m if figures.rmse_pen_down_m is not None else float("nan")
    return writing_verdict(rmse, figures.iou, bounds)


def flight_doc(
    args: argparse.Namespace,
    glyph: Any,
    plan: WritingPlan,
    flown: FlownWriting,
    score: WritingScore,
    wall_s: float,
) -> dict[str, Any]:
    """The metrics document of one flight of ``glyph`` as laid out (``metrics.json``,
    ``--json``), with the kind's own figures that were measured (:func:`measured_extra`)."""
    figures = measured(score, flown)
    bounds = WritingBounds(args.rmse_max, args.iou_min)
    problem = verdict(flown, figures, bounds)
    sim_time_s = float(flown.t_s[-1] - flown.t_s[0]) if flown.t_s.size else 0.0
    doc: dict[str, Any] = {
        "kind": args.kind,
        "label": glyph.label,
        "planned_ink_size_m": ink_size_m(glyph),
        "rmse_pen_down_m": figures.rmse_pen_down_m,
        "rmse_m": score.rmse_m,
        "max_error_m": score.max_error_m,
        "iou": figures.iou,
        "wrote_ink": figures.wrote_ink,
        "sim_time_s": sim_time_s,
        "wall_time_s": wall_s,
        "real_time_factor": sim_time_s / wall_s if wall_s > 0 else None,
        "seed": args.seed,
        "writing_area_m": [args.width, args.height],
        "margin_m": args.margin,
        "planned_duration_s": plan.duration_s,
        "aborted": flown.abort_reason,
        "within_bounds": problem is None,
        "problem": problem,
        "bounds": {"rmse_pen_down_max_m": args.rmse_max, "iou_min": args.iou_min},
    }
    extra = measured_extra(score.extra, figures)
    doc.update({name: value for name, value in extra.items() if name not in doc})
    return doc


def print_outcome(args: argparse.Namespace, doc: dict[str, Any]) -> int:
    """The summary (``--json``: the document, one line) on stdout, a failed bound on stderr;
    the exit status (0 within bounds, 1 not)."""
    from cli.summary import flight_lines

    if args.json:
        print(json.dumps(doc, ensure_ascii=False, default=_plain))
    else:
        print("\n".join(flight_lines(doc)))
    if doc["problem"] is not None:
        print(f"skyquill fly: writing out of bounds: {doc['problem']}", file=sys.stderr)
        return 1
    return 0


def _plain(value: Any) -> Any:
    """A numpy scalar or array as JSON (``json.dumps``'s ``default``)."""
    if hasattr(value, "tolist"):
        return value.tolist()
    return str(value)


def metrics_text(doc: dict[str, Any]) -> str:
    """``metrics.json``'s text."""
    return json.dumps(doc, indent=2, ensure_ascii=False, default=_plain) + "\n"

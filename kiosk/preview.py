"""What the vehicle will write: the glyph laid out on the writing area and planned.

Plans through the one job-planning function (:func:`vehicles.jobs.plan_glyph`) for the kinds of
the show as the orchestrator plans for them (:attr:`kiosk.settings.KioskSettings.preview_kinds`),
in board order until one accepts: the preview is the plan of the first kind whose planner accepts
the submission, which is refused only when every kind's planner refuses it, for the first kind's
reason (a flight time over the show's limit before a bare "cannot fly"). Returns plain JSON
for the page: turning points and the planned path in the writing area's own frame (metres,
origin at the centre, y up), with the planned line width at each point where the kind writes
with a width, and the one-line reasons of the kinds tried before (text).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from kiosk import wording
from kiosk.errors import RejectedError
from kiosk.limits import Submission
from kiosk.settings import KioskSettings
from planner.errors import PlannerError
from planner.glyphs import Glyph, parse_strokes_json, text_glyph
from planner.glyphs.layout import MIN_INK_FRACTION, ink_fraction
from vehicles.jobs import JobPlan, JobSetup

PATH_POINTS_MAX = 800
"""Most points of the path sent to the page (decimated from the planner's samples)."""
REASON_CHARS_MAX = 200
"""Longest refusal reason of a kind given to the page, in characters."""


def glyph_of(submission: Submission) -> Glyph:
    """The glyph of a checked submission; a drawing that cannot be read is a RejectedError."""
    if submission.text is not None:
        try:
            return text_glyph(submission.text)
        except PlannerError:
            raise RejectedError("no_glyph", wording.UNPLANNABLE, status=422) from None
    try:
        return parse_strokes_json(submission.strokes or {}, source_name="drawing")
    except PlannerError as exc:
        raise RejectedError(
            "bad_drawing",
            wording.BAD_DRAWING,
            status=422,
            stroke_index=exc.stroke_index,
            point_index=exc.point_index,
        ) from None


def plan_preview(submission: Submission, settings: KioskSettings) -> dict[str, Any]:
    """Turning points, path and duration of the submission as the vehicle will write it."""
    glyph = glyph_of(submission)
    fraction = ink_fraction(glyph)
    if fraction is not None and fraction < MIN_INK_FRACTION:
        raise RejectedError("too_small", wording.TOO_SMALL, status=422)
    setup, job, refusals = _plan_kinds(glyph, settings.kinds(), settings.max_flight_s)
    planned, fitted = job.plan, job.glyph
    samples = planned.samples
    board_xy = planned.surface.to_surface(samples.position_m_enu)
    step = max(1, int(np.ceil(board_xy.shape[0] / PATH_POINTS_MAX)))
    keep = np.unique(np.r_[np.arange(0, board_xy.shape[0], step), board_xy.shape[0] - 1])
    # keep every pen change so the page draws strokes where they really start and stop
    pen = samples.pen_down
    changes = np.flatnonzero(np.diff(pen.astype(np.int8)))
    keep = np.union1d(keep, np.r_[changes, changes + 1])
    path: list[list[Any]] = [
        [round(float(x), 4), round(float(y), 4), bool(p)]
        for (x, y), p in zip(board_xy[keep], pen[keep], strict=True)
    ]
    if planned.width_m is not None:
        for point, w in zip(path, planned.width_m[keep], strict=True):
            point.append(round(float(w), 5))
    turning = [np.round(tp, 4).tolist() for tp in planned.turning_points_m]
    width_range_m = setup.kind.width_range_m(setup.settings)
    return {
        "label": submission.label,
        "writing_area_m": list(setup.writing_area_m),
        "stroke_count": len(fitted.strokes),
        "turning_points": turning,
        "turning_point_count": sum(len(tp) for tp in turning),
        "path": path,
        "duration_s": round(planned.duration_s, 2),
        "kind": setup.kind.name,
        "widths": planned.width_m is not None,
        "width_range_m": width_range_m and list(width_range_m),
        "widths_clamped": int(planned.feasibility.get("widths_clamped", 0)),
        "kinds_refused": refusals,
    }


def _plan_kinds(
    glyph: Glyph, kinds: tuple[JobSetup, ...], max_flight_s: float
) -> tuple[JobSetup, JobPlan, dict[str, str]]:
    """The first kind whose planner accepts ``glyph`` within ``max_flight_s`` of writing, its
    plan, and the one-line reasons of the kinds tried before it (the kinds after it are not
    planned: a preview waits for one plan, not for every kind's); RejectedError for the first
    kind's reason when every kind refuses, but a kind's flight time over the limit before an
    earlier kind's bare "cannot fly this one" (fewer strokes is something a visitor can do)."""
    refusals: dict[str, str] = {}
    first: RejectedError | None = None
    for setup in kinds:
        try:
            job = setup.plan(glyph)
        except PlannerError as exc:
            rejection, reason = _rejection(exc), str(exc)
        else:
            duration_s = job.plan.duration_s
            if duration_s <= max_flight_s:
                return setup, job, refusals
            message = wording.TOO_LONG_FLIGHT.format(
                seconds=round(duration_s), limit=round(max_flight_s)
            )
            rejection = RejectedError("too_long", message, status=422, flight_s=duration_s)
            reason = f"writes for {duration_s:.0f} s, over the show's {max_flight_s:.0f} s"
        refusals[setup.kind.name] = _one_line(reason)
        if first is None or (first.code == "unplannable" and rejection.code == "too_long"):
            first = rejection
    raise first or RejectedError("unplannable", wording.UNPLANNABLE, status=422)


def _rejection(exc: PlannerError) -> RejectedError:
    """What the page is told when no kind can plan the submission, from a kind's refusal."""
    if exc.field == "w":
        return RejectedError(
            "bad_width",
            wording.BAD_WIDTH,
            status=422,
            stroke_index=exc.stroke_index,
            point_index=exc.point_index,
        )
    return RejectedError("unplannable", wording.UNPLANNABLE, status=422)


def _one_line(reason: str) -> str:
    """A kind's refusal in one line of at most ``REASON_CHARS_MAX`` characters (plain text)."""
    line = " ".join(reason.split())
    return line if len(line) <= REASON_CHARS_MAX else line[: REASON_CHARS_MAX - 1] + "…"


def plan_phrase_preview(submission: Submission, settings: KioskSettings) -> dict[str, Any]:
    """A phrase: each character planned as a job of its own (one drone each, on adjacent
    boards in reading order), and the row they are written on (``row``: boards from the left)."""
    characters = [
        plan_preview(Submission(text=char, strokes=None, label=char), settings)
        for char in submission.text or ""
    ]
    return {
        "phrase": True,
        "label": submission.label,
        "row": settings.limits.max_phrase_chars,
        "characters": characters,
        "writing_area_m": characters[0]["writing_area_m"],
        "stroke_count": sum(c["stroke_count"] for c in characters),
        "turning_point_count": sum(c["turning_point_count"] for c in characters),
        "duration_s": max(c["duration_s"] for c in characters),  # they write at once
    }


def make_previewer(settings: KioskSettings) -> Callable[[Submission], dict[str, Any]]:
    """``plan_preview`` (``plan_phrase_preview`` for a phrase) bound to ``settings`` (what
    :func:`kiosk.app.create_app` expects)."""

    def previewer(submission: Submission) -> dict[str, Any]:
        if submission.phrase:
            return plan_phrase_preview(submission, settings)
        return plan_preview(submission, settings)

    return previewer

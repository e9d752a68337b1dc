"""What the vehicle will write: the glyph laid out on the writing area and planned.

Plans through the one job-planning function (:func:`vehicles.jobs.plan_glyph`) for the kind
writing on the show's first board (the brush quadrotor with the kiosk's planner options, or the
hexarotor with its pen); returns plain JSON for the page: turning points and the planned path in
the writing area's own frame (metres, origin at the centre, y up), with the planned line width at
each point where the kind writes with a width.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from kiosk import wording
from kiosk.errors import RejectedError
from kiosk.limits import Submission
from kiosk.settings import BRUSH_KIND, KioskSettings
from planner.errors import PlannerError
from planner.glyphs import Glyph, parse_strokes_json, text_glyph
from planner.glyphs.layout import MIN_INK_FRACTION, ink_fraction
from vehicles.jobs import JobPlan, plan_glyph
from vehicles.registry import vehicle_kind
from vehicles.surface import Surface

PATH_POINTS_MAX = 800
"""Most points of the path sent to the page (decimated from the planner's samples)."""
PATH_RATE_HZ = 100.0
"""Rate at which the planned trajectory is sampled before decimation, [Hz]."""


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
    width_m, height_m = settings.writing_area_m
    glyph = glyph_of(submission)
    fraction = ink_fraction(glyph)
    if fraction is not None and fraction < MIN_INK_FRACTION:
        raise RejectedError("too_small", wording.TOO_SMALL, status=422)
    try:
        job = _plan(glyph, settings)
    except PlannerError as exc:
        if exc.field == "w":
            raise RejectedError(
                "bad_width",
                wording.BAD_WIDTH,
                status=422,
                stroke_index=exc.stroke_index,
                point_index=exc.point_index,
            ) from None
        raise RejectedError("unplannable", wording.UNPLANNABLE, status=422) from None
    planned, fitted = job.plan, job.glyph
    if planned.duration_s > settings.max_flight_s:
        message = wording.TOO_LONG_FLIGHT.format(
            seconds=round(planned.duration_s), limit=round(settings.max_flight_s)
        )
        raise RejectedError("too_long", message, status=422)
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
    return {
        "label": submission.label,
        "writing_area_m": [width_m, height_m],
        "stroke_count": len(fitted.strokes),
        "turning_points": turning,
        "turning_point_count": sum(len(tp) for tp in turning),
        "path": path,
        "duration_s": round(planned.duration_s, 2),
        "kind": settings.preview_kind,
        "widths": planned.width_m is not None,
        "width_range_m": settings.width_range_m and list(settings.width_range_m),
        "widths_clamped": int(planned.feasibility.get("widths_clamped", 0)),
    }


def _plan(glyph: Glyph, settings: KioskSettings) -> JobPlan:
    """The job as a vehicle of the preview's kind would plan it, on the writing area's own
    frame."""
    kind = vehicle_kind(settings.preview_kind)
    kind_settings = settings.preview_kind_settings or kind.settings(None, None)
    if kind.name == BRUSH_KIND:
        kind_settings = replace(
            kind_settings, plan=replace(settings.plan, sample_rate_hz=PATH_RATE_HZ)
        )
    board = settings.plan.board
    surface = Surface.of(kind.orientation, board.center_m_enu, board.yaw_rad)
    return plan_glyph(
        kind, kind_settings, surface, glyph, settings.writing_area_m, settings.margin_m
    )


def make_previewer(settings: KioskSettings) -> Callable[[Submission], dict[str, Any]]:
    """``plan_preview`` bound to ``settings`` (what :func:`kiosk.app.create_app` expects)."""

    def previewer(submission: Submission) -> dict[str, Any]:
        return plan_preview(submission, settings)

    return previewer

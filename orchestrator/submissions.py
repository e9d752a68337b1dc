"""Submissions: validated by the planner's glyph parsing before acknowledgement; durations.

:func:`validate_submission` turns a :class:`SubmitRequest` into an :class:`Accepted` (label, glyph,
rough duration) or raises :class:`SubmissionError` whose ``info`` names the field, stroke and point
at fault. :func:`planned_durations_s` runs each kind's own planning (``vehicles.jobs.plan_job``)
(slow: run it in a worker thread, after the acknowledgement).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import msgspec
import numpy as np

from bus.messages import ErrorInfo, SubmitRequest
from bus.public_text import drawing_label
from orchestrator.kinds import KindPlans
from planner.errors import PlannerError
from planner.glyphs import Glyph, parse_strokes_json, text_glyph
from showfile import Show
from vehicles.jobs import kind_writers, lay_out, plan_job

PRIORITY_RANGE = (-10, 10)
PEN_UP_OVERHEAD_S = 1.5
"""Rough time per stroke for lifting, moving and lowering the brush, [s]."""


class SubmissionError(ValueError):
    """A submission that cannot be accepted; ``info`` says why and where."""

    def __init__(self, info: ErrorInfo) -> None:
        self.info = info
        super().__init__(info.message)


@dataclass(frozen=True)
class Accepted:
    """A submission that passed validation."""

    label: str
    """Short human label."""
    glyph: Glyph
    """What will be written, in its source units."""
    estimate_s: float
    """Rough writing duration in sim seconds (before the planner has run)."""
    characters: tuple[Accepted, ...] = ()
    """A phrase's characters, each accepted as a job of its own, in reading order (empty: not a
    phrase)."""


def _planner_error(exc: PlannerError, code: str, field_prefix: str) -> SubmissionError:
    field = (
        f"{field_prefix}.{exc.field}" if exc.field and exc.field != field_prefix else field_prefix
    )
    return SubmissionError(
        ErrorInfo(
            code=code,
            message=str(exc),
            field=field,
            stroke_index=exc.stroke_index,
            point_index=exc.point_index,
        )
    )


def _glyph(request: SubmitRequest) -> Glyph:
    if (request.text is None) == (request.strokes is None):
        raise SubmissionError(
            ErrorInfo(code="invalid", message="give exactly one of text and strokes", field="text")
        )
    if request.text is not None:
        if not request.text.strip():
            raise SubmissionError(
                ErrorInfo(code="invalid_text", message="empty text", field="text")
            )
        try:
            return text_glyph(request.text)
        except PlannerError as exc:
            raise _planner_error(exc, "invalid_text", "text") from None
    try:
        return parse_strokes_json(dict(request.strokes or {}), source_name="submission")
    except PlannerError as exc:
        raise _planner_error(exc, "invalid_strokes", "strokes") from None


def validate_submission(request: SubmitRequest, show: Show) -> Accepted:
    """Check a submission fully (glyph parsing included); raises :class:`SubmissionError`.
    Its names and length were checked when it was decoded (``bus.public_text``)."""
    low, high = PRIORITY_RANGE
    if not low <= request.priority <= high:
        raise SubmissionError(
            ErrorInfo(
                code="invalid", message=f"priority must be in {low}..{high}", field="priority"
            )
        )
    if request.phrase:
        return _phrase(request, show)
    glyph = _glyph(request)
    _check_fits(glyph, request, show)
    text = request.text
    label = text.strip() if text is not None else drawing_label(len(glyph.strokes))
    return Accepted(label=label[:80], glyph=glyph, estimate_s=rough_duration_s(glyph, show))


def _phrase(request: SubmitRequest, show: Show) -> Accepted:
    """A phrase: typed characters, no spaces, at most one per board of the row; each a job."""
    text = request.text or ""
    row = len(show.boards)
    if request.strokes is not None or not text:
        why = "a phrase is typed text: give text, not strokes"
    elif any(char.isspace() for char in text):
        why = "a phrase has no spaces: one character per board"
    elif len(text) > row:
        why = f"a phrase of {len(text)} characters is longer than the row: at most {row}"
    else:
        why = None
    if why is not None:
        raise SubmissionError(ErrorInfo(code="invalid_text", message=why, field="text"))
    characters = []
    for char in text:
        one = msgspec.structs.replace(request, text=char, phrase=False)
        characters.append(validate_submission(one, show))
    estimate_s = max(c.estimate_s for c in characters)
    return Accepted(
        label=text, glyph=_glyph(request), estimate_s=estimate_s, characters=tuple(characters)
    )


def _check_fits(glyph: Glyph, request: SubmitRequest, show: Show) -> None:
    """Refuse at submission what no vehicle could lay out on its board (e.g. no extent)."""
    code, field = (
        ("invalid_text", "text") if request.text is not None else ("invalid_strokes", "strokes")
    )
    for board in show.boards:
        try:
            lay_out(glyph, board.writing_area_m, show.planning.margin_m)
        except PlannerError as exc:
            raise _planner_error(exc, code, field) from None


def _fitted(glyph: Glyph, show: Show) -> Glyph:
    return lay_out(glyph, show.boards[0].writing_area_m, show.planning.margin_m)


def rough_duration_s(glyph: Glyph, show: Show) -> float:
    """Ink length at 60 % of the speed limit plus a pen-up allowance per stroke, [s]."""
    try:
        fitted = _fitted(glyph, show)
    except PlannerError:
        return 30.0
    length_m = sum(
        float(np.sum(np.linalg.norm(np.diff(stroke, axis=0), axis=1))) for stroke in fitted.strokes
    )
    speed = 0.6 * show.limits.v_max_mps
    return length_m / speed + PEN_UP_OVERHEAD_S * len(fitted.strokes)


def planned_durations_s(glyph: Glyph, show: Show) -> KindPlans:
    """The real plan of the vehicle that stands for each kind of the show
    (``vehicles.jobs.kind_writers``, as in the kiosk's preview): durations, and the kinds that
    cannot plan it."""
    durations: dict[str, float] = {}
    refused: set[str] = set()
    for kind, vehicle_id in kind_writers(show).items():
        try:
            duration = float(plan_job(show, vehicle_id, glyph).plan.duration_s)
        except PlannerError:
            refused.add(kind)
            continue
        if math.isfinite(duration):
            durations[kind] = duration
    return KindPlans(durations, frozenset(refused))

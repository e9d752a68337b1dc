"""Submissions are checked whole at submit: what would fail on the vehicle is refused there."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from bus.messages import SubmitRequest
from orchestrator.submissions import SubmissionError, validate_submission
from showfile import Show, load_show

SOLO = Path(__file__).resolve().parents[1] / "shows" / "solo.yaml"


@pytest.fixture(scope="module")
def show() -> Show:
    return load_show(SOLO)


def _doc(*strokes: list[list[float]]) -> dict[str, Any]:
    return {"units": "px", "y_axis": "down", "strokes": list(strokes)}


def _refusal(request: SubmitRequest, show: Show) -> SubmissionError:
    with pytest.raises(SubmissionError) as err:
        validate_submission(request, show)
    return err.value


def test_a_drawing_with_huge_coordinates_is_refused_naming_stroke_and_point(show: Show) -> None:
    request = SubmitRequest(strokes=_doc([[0, 0], [10, 10]], [[0, 0], [5, 5], [1e308, 1]]))
    info = _refusal(request, show).info
    assert (info.code, info.field, info.stroke_index, info.point_index) == (
        "invalid_strokes",
        "strokes",
        1,
        2,
    )
    assert "1e+06" in info.message


def test_a_drawing_too_small_to_lay_out_is_refused_at_submit(show: Show) -> None:
    request = SubmitRequest(strokes=_doc([[0, 0], [5e-324, 0]]))  # distinct, but no usable extent
    info = _refusal(request, show).info
    assert info.code == "invalid_strokes" and "too small" in info.message


def test_drawings_at_the_coordinate_bound_and_texts_are_accepted(show: Show) -> None:
    at_bound = validate_submission(SubmitRequest(strokes=_doc([[-1e6, 1e6], [1e6, -1e6]])), show)
    assert at_bound.label == "drawing (1 stroke)" and at_bound.estimate_s > 0
    assert validate_submission(SubmitRequest(text="永"), show).label == "永"


def test_a_drawings_label_is_its_stroke_count_never_the_documents_own(show: Show) -> None:
    """docs/protocol.md: a drawing's label is ``drawing (N strokes)``, whatever its document
    calls itself (public text the operator never asked to read)."""
    doc = {"units": "m", "y_axis": "up", "label": "my tick"}
    doc["strokes"] = [[[0, 0], [1, 0]], [[0, 0], [0, 1]]]  # type: ignore[assignment]
    accepted = validate_submission(SubmitRequest(strokes=doc), show)
    assert accepted.label == "drawing (2 strokes)"

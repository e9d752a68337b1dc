"""A show of several kinds: the kiosk plans a submission for its kinds as the orchestrator plans
it (``vehicles.jobs``), in board order until one can write it, shows that plan with the reasons of
the kinds tried before, and refuses it only when every kind refuses, for the first kind's
reason. The widths offered to the drawing pad are those of the kinds that write widths. With the
real planners (the sponge pen refuses a width before its solver runs)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest

from kiosk import wording
from kiosk.errors import RejectedError
from kiosk.limits import Submission
from kiosk.preview import plan_preview
from kiosk.settings import PATH_RATE_HZ, settings_from_show
from orchestrator.submissions import planned_durations_s
from planner.glyphs import parse_strokes_json, text_glyph
from showfile import load_show, parse_show
from vehicles.jobs import plan_job

SHOWS = Path(__file__).resolve().parents[1] / "shows"
BRUSH, WALL, GROUND = "quadrotor-brush", "hexarotor-sponge", "omni-wheel"

WALL_BOARD = (
    "{id: wall, orientation: vertical, center_m_enu: [2.0, 1.0, 1.5], size_m: [2.0, 1.5],"
    " writing_area_m: [0.5, 0.5]}"
)
BRUSH_BOARD = (
    "{id: b1, center_m_enu: [-3.0, 0.0, 0.75], size_m: [1.4, 1.4], writing_area_m: [1.2, 1.2]}"
)
SHOW = """\
show_id: t
boards:
  - {first}
  - {second}
vehicles:
  - {{id: uav1, kind: quadrotor-brush, board: b1, home_m_enu: [-3.0, -1.2, 0.0]}}
  - {{id: calligrapher, kind: hexarotor-sponge, board: wall, home_m_enu: [2.0, -0.5, 0.0]}}
planning: {{total_time_s: {total_time_s}}}
"""
"""mixed.yaml's wall and first brush board; the vehicles listed brush first, whatever the
boards' order (the kinds come in board order)."""

WIDE = [{"x": 0.0, "y": 0.0, "w": 0.03}, {"x": 0.3, "y": 0.0, "w": 0.03}]
"""A 30 mm stroke: refused by the sponge pen only (as in test_orchestrator_kinds)."""


def show_of(*, wall_first: bool = True, total_time_s: str = "null") -> Any:
    first, second = (WALL_BOARD, BRUSH_BOARD) if wall_first else (BRUSH_BOARD, WALL_BOARD)
    return parse_show(SHOW.format(first=first, second=second, total_time_s=total_time_s))


def drawing(*strokes: list[dict[str, float]]) -> Submission:
    return Submission(
        text=None, strokes={"units": "m", "y_axis": "up", "strokes": list(strokes)}, label="d"
    )


def test_a_drawing_the_first_boards_kind_refuses_is_previewed_for_a_kind_that_can_write_it() -> (
    None
):
    settings = settings_from_show(show_of())
    assert [k.kind.name for k in settings.preview_kinds] == [WALL, BRUSH]  # board order
    preview = plan_preview(drawing(WIDE), settings)
    assert preview["kind"] == BRUSH
    assert preview["writing_area_m"] == [1.2, 1.2]  # the brush's board, not the wall's
    assert preview["widths"] is False and preview["width_range_m"] is None
    (reason,) = preview["kinds_refused"].values()
    assert list(preview["kinds_refused"]) == [WALL]
    assert "30.00 mm is outside the pen's range" in reason and "\n" not in reason
    # what the brush vehicle itself plans
    flown = plan_job(show_of(), "uav1", parse_strokes_json(drawing(WIDE).strokes or {})).plan
    assert preview["duration_s"] == pytest.approx(flown.duration_s, abs=0.01)


def test_a_drawing_every_kind_refuses_is_rejected_for_the_first_kinds_reason() -> None:
    # a second to write a 1.1 m line: beyond the brush's limits; 30 mm: beyond the sponge's pen
    for wall_first, code in ((True, "bad_width"), (False, "unplannable")):
        settings = settings_from_show(show_of(wall_first=wall_first, total_time_s="1.0"))
        with pytest.raises(RejectedError) as err:
            plan_preview(drawing(WIDE), settings)
        assert err.value.code == code, wall_first
        if code == "bad_width":
            assert err.value.message == wording.BAD_WIDTH
            assert (err.value.stroke_index, err.value.point_index) == (0, 0)
        else:
            assert err.value.message == wording.UNPLANNABLE
    # a drawing the sponge writes is not refused for the brush's limits
    narrow = [{**p, "w": 0.009} for p in WIDE]
    preview = plan_preview(drawing(narrow), settings_from_show(show_of(total_time_s="1.0")))
    assert preview["kind"] == WALL and preview["kinds_refused"] == {}  # the brush not planned


def test_the_kiosk_previews_the_first_kind_the_orchestrator_finds_able_to_write_a_glyph() -> None:
    show = load_show(SHOWS / "mixed.yaml")
    settings = settings_from_show(show)
    preview = plan_preview(drawing(WIDE), settings)
    plans = planned_durations_s(parse_strokes_json(drawing(WIDE).strokes or {}), show)
    assert plans.refused == {WALL} and list(plans.durations_s) == [BRUSH, GROUND]
    assert preview["kind"] == BRUSH and preview["kinds_refused"] == {}  # the first board's
    assert preview["duration_s"] == pytest.approx(plans.durations_s[BRUSH], abs=0.01)
    # the drawing pad offers the sponge's widths though a brush writes on the first board
    assert settings.width_range_m == pytest.approx((0.005, 0.014))


def test_the_preview_plans_with_the_vehicles_settings_sampled_for_the_page() -> None:
    """The kiosk's planner options are the vehicle's own (no brush special case): only the
    sampling of the path for the page differs."""
    show = load_show(SHOWS / "solo.yaml")
    planning = show.planning.model_copy(update={"clearance_m": 0.0, "sample_rate_hz": 200.0})
    show = show.model_copy(update={"planning": planning})
    (brush,) = settings_from_show(show).preview_kinds
    vehicle = brush.kind.settings(show, "uav1")
    assert brush.settings.plan == replace(vehicle.plan, sample_rate_hz=PATH_RATE_HZ)
    assert brush.settings.flight == vehicle.flight
    preview = plan_preview(Submission(text="L", strokes=None), settings_from_show(show))
    flown = plan_job(show, "uav1", text_glyph("L")).plan
    assert preview["duration_s"] == pytest.approx(flown.duration_s, abs=0.01)
    assert flown.samples.t_s.size > 1.9 * PATH_RATE_HZ * flown.duration_s  # 200 Hz


def test_a_single_kind_shows_preview_keeps_its_fields_and_adds_the_refusals() -> None:
    show = load_show(SHOWS / "airshow-2014.yaml")
    settings = settings_from_show(show)
    assert settings.width_range_m is None and settings.writing_area_m == (1.2, 1.2)
    preview = plan_preview(Submission(text="永", strokes=None, label="永"), settings)
    assert set(preview) == {
        "label", "writing_area_m", "stroke_count", "turning_points", "turning_point_count",
        "path", "duration_s", "kind", "widths", "width_range_m", "widths_clamped",
        "kinds_refused",
    }  # fmt: skip
    assert preview["kind"] == BRUSH
    assert preview["kinds_refused"] == {}
    assert preview["writing_area_m"] == [1.2, 1.2] and preview["width_range_m"] is None
    assert {len(p) for p in preview["path"]} == {3}
    flown = plan_job(show, "uav1", text_glyph("永")).plan
    assert preview["duration_s"] == pytest.approx(flown.duration_s, abs=0.01)
    assert preview["turning_point_count"] == sum(len(tp) for tp in flown.turning_points_m)


def test_a_kind_too_slow_for_the_kiosks_limit_leaves_it_to_the_next() -> None:
    narrow = drawing([{**p, "w": 0.009} for p in WIDE])
    slow_brush = settings_from_show(show_of(wall_first=False, total_time_s="60.0"))
    preview = plan_preview(narrow, replace(slow_brush, max_flight_s=30.0))
    assert preview["kind"] == WALL and preview["duration_s"] < 30.0
    assert preview["kinds_refused"] == {BRUSH: "writes for 60 s, over the show's 30 s"}
    with pytest.raises(RejectedError) as err:  # every kind too slow: the first one's seconds
        plan_preview(narrow, replace(slow_brush, max_flight_s=preview["duration_s"] / 2))
    assert err.value.code == "too_long" and "about 60 seconds" in err.value.message

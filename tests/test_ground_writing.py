"""A floor character written by the ground writer in MuJoCo, within its bound."""

from __future__ import annotations

import numpy as np
import pytest

from planner.glyphs.layout import fit_to_area
from planner.glyphs.text import text_glyph
from vehicles.kind import StrokeInput
from vehicles.omni_wheel.floor_plan import DEFAULT_SETTINGS, plan_floor
from vehicles.omni_wheel.writing import drive_plan, score_floor
from vehicles.surface import Surface


def _strokes(text: str, size_m: float) -> list[StrokeInput]:
    glyph = fit_to_area(text_glyph(text), width_m=size_m, height_m=size_m)
    return [StrokeInput(np.asarray(s, dtype=np.float64)) for s in glyph.strokes]


def test_plan_lies_on_the_floor_within_the_ground_limits() -> None:
    surface = Surface.of("floor", (3.0, 1.0, 0.0), 0.3)
    plan = plan_floor(_strokes("十", 1.0), surface, DEFAULT_SETTINGS)
    assert np.all(plan.samples.position_m_enu[:, 2] == 0.0)
    speed = np.linalg.norm(plan.samples.velocity_mps_enu, axis=1)
    assert speed.max() <= DEFAULT_SETTINGS.speed_max_mps + 1e-6
    # the pen-down reference passes over the strokes laid on the surface (1 m cross, centred)
    down = surface.to_surface(plan.samples.position_m_enu[plan.samples.pen_down])
    assert np.abs(down).max() == pytest.approx(0.5, abs=0.03)


@pytest.mark.slow
def test_floor_character_is_written_within_its_bound() -> None:
    surface = Surface.of("floor", (3.0, 1.0, 0.0), 0.0)
    plan = plan_floor(_strokes("一", 1.0), surface, DEFAULT_SETTINGS)
    flown = drive_plan(plan, DEFAULT_SETTINGS, seed=1)
    score = score_floor(plan, flown, DEFAULT_SETTINGS.marker_width_m)
    assert score.rmse_pen_down_m <= 0.005
    assert score.iou is not None and score.iou >= 0.85
    # the marker only inks where the reference meant it to, after the lift's delay
    assert not np.any(flown.ink_width_m[~flown.pen_down] > 0.0)

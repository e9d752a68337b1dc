"""Studies over climb runs: the bisection of the highest step and the means over seeds, against a
stand-in climb whose answer is known (the MuJoCo climbs themselves: test_ground_sim.py)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from vehicles.omni_wheel import climb_study
from vehicles.omni_wheel.climb import ClimbResult
from vehicles.omni_wheel.geometry import OmniGeometry

GEO = OmniGeometry()


def _result(climbed: bool, slip: float, height_m: float = 0.1) -> ClimbResult:
    per_wheel = np.full(7, slip)
    per_wheel[1] = np.nan  # the sideways wheel never counts
    return ClimbResult("proposed", height_m, climbed, 1.0, per_wheel, 2.0 * per_wheel, {})


@pytest.mark.parametrize("ceiling_m", [0.0937, 0.041, 0.1999])
def test_highest_step_is_found_within_its_tolerance(
    ceiling_m: float, monkeypatch: pytest.MonkeyPatch
) -> None:
    heights: list[float] = []

    def fake(method: str, height_m: float, **_: Any) -> ClimbResult:
        heights.append(height_m)
        return _result(height_m <= ceiling_m, 0.1, height_m)

    monkeypatch.setattr(climb_study, "climb", fake)
    found = climb_study.highest_step_m("proposed", GEO, tol_m=0.005)
    assert ceiling_m - 0.005 < found <= ceiling_m
    assert len(heights) <= 7  # one probe at the floor, then log2(160 mm / 5 mm) halvings


def test_a_floor_not_climbed_gives_zero(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(climb_study, "climb", lambda *a, **k: _result(False, 0.5))
    assert climb_study.highest_step_m("standard", GEO) == 0.0


def test_means_over_seeds_average_the_wheel_groups() -> None:
    runs = climb_study.SeededClimbs((_result(True, 0.1), _result(False, 0.3)))
    assert runs.climbed == 1
    assert runs.mean("slip") == pytest.approx(0.2)
    assert runs.mean("rotation_error") == pytest.approx(0.4)

"""The feasibility report's dense checks (planner.feasibility) against plain sampling."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.bspline import ClampedCubicSpline
from planner.feasibility import assess, distance_to_polyline
from planner.limits import VehicleLimits


def _spline(m: int, duration_s: float, seed: int) -> ClampedCubicSpline:
    ctrl = np.random.default_rng(seed).normal(scale=0.3, size=(m + 3, 3))
    return ClampedCubicSpline(control_points=ctrl, duration_s=duration_s)


@pytest.mark.parametrize(("m", "duration_s", "seed"), [(8, 3.0, 1), (40, 7.9, 2), (123, 24.6, 3)])
def test_the_report_reads_every_sample(m: int, duration_s: float, seed: int) -> None:
    """Acceleration read at the knots, speed and height from the span polynomials: the same
    shares, peak and lowest height as evaluating the spline at every sample (each span from end
    to end at >= 1 kHz)."""
    spline = _spline(m, duration_s, seed)
    limits = VehicleLimits()
    per_span = max(2, math.ceil(1000.0 * duration_s / m) + 1)
    x = np.linspace(0.0, 1.0, per_span)
    t = ((np.arange(m)[:, None] + x[None, :]) / spline.alpha).ravel()
    lower, upper = limits.accel_bounds_mps2()
    accel = spline.evaluate(t, 2)
    share_a = float(np.max(np.maximum(accel / np.asarray(upper), accel / np.asarray(lower))))
    speed = np.linalg.norm(spline.evaluate(t, 1), axis=1)
    report = assess(
        spline,
        limits,
        turning_residuals_m=np.zeros((0, 3)),
        turning_stroke_index=np.zeros(0, dtype=np.int64),
        n_strokes=0,
        board_surface_z_m=-1.0,
    )
    assert report.sampled_accel_share == pytest.approx(share_a, rel=1e-12)
    assert report.sampled_speed_share == pytest.approx(np.max(speed) / limits.v_max_mps, rel=1e-12)
    assert report.peak_speed_mps == pytest.approx(np.max(speed), rel=1e-12)
    assert report.peak_speed_time_s == pytest.approx(t[np.argmax(speed)], abs=1e-12)
    lowest = float(np.min(spline.evaluate(t)[:, 2]))
    assert report.min_height_above_board_m == pytest.approx(lowest + 1.0, rel=1e-12)


def test_distance_to_polyline_known_answers() -> None:
    """An L (with a repeated vertex): beside a leg, beyond an end, at the corner, on it."""
    polyline = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 0.0], [2.0, 1.0]])
    points = np.array([[1.0, 0.5], [-3.0, 4.0], [3.0, -1.0], [2.5, 0.5], [2.0, 0.7]])
    expected = [0.5, 5.0, math.sqrt(2.0), 0.5, 0.0]
    np.testing.assert_allclose(distance_to_polyline(points, polyline), expected, atol=1e-15)
    one = distance_to_polyline(points, polyline[:1])
    np.testing.assert_allclose(one, np.linalg.norm(points, axis=1))

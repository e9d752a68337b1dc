"""The feasibility report's dense checks (planner.feasibility) against plain sampling."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.bspline import ClampedCubicSpline
from planner.feasibility import distance_to_polyline, sampled_shares
from planner.limits import VehicleLimits


def _spline(m: int, duration_s: float, seed: int) -> ClampedCubicSpline:
    ctrl = np.random.default_rng(seed).normal(scale=0.3, size=(m + 3, 3))
    return ClampedCubicSpline(control_points=ctrl, duration_s=duration_s)


@pytest.mark.parametrize(("m", "duration_s", "seed"), [(8, 3.0, 1), (40, 7.9, 2), (123, 24.6, 3)])
def test_sampled_shares_are_those_of_every_sample(m: int, duration_s: float, seed: int) -> None:
    """Acceleration read at the knots and speed from the span polynomials: the same shares as
    evaluating the spline at every sample (each span from end to end at >= 1 kHz)."""
    spline = _spline(m, duration_s, seed)
    limits = VehicleLimits()
    per_span = max(2, math.ceil(1000.0 * duration_s / m) + 1)
    x = np.linspace(0.0, 1.0, per_span)
    t = ((np.arange(m)[:, None] + x[None, :]) / spline.alpha).ravel()
    lower, upper = limits.accel_bounds_mps2()
    accel = spline.evaluate(t, 2)
    share_a = float(np.max(np.maximum(accel / np.asarray(upper), accel / np.asarray(lower))))
    share_v = float(np.max(np.linalg.norm(spline.evaluate(t, 1), axis=1))) / limits.v_max_mps
    got_a, got_v = sampled_shares(spline, limits)
    assert got_a == pytest.approx(share_a, rel=1e-12)
    assert got_v == pytest.approx(share_v, rel=1e-12)


def test_distance_to_polyline_known_answers() -> None:
    """An L (with a repeated vertex): beside a leg, beyond an end, at the corner, on it."""
    polyline = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 0.0], [2.0, 1.0]])
    points = np.array([[1.0, 0.5], [-3.0, 4.0], [3.0, -1.0], [2.5, 0.5], [2.0, 0.7]])
    expected = [0.5, 5.0, math.sqrt(2.0), 0.5, 0.0]
    np.testing.assert_allclose(distance_to_polyline(points, polyline), expected, atol=1e-15)
    one = distance_to_polyline(points, polyline[:1])
    np.testing.assert_allclose(one, np.linalg.norm(points, axis=1))

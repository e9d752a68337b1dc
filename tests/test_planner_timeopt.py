"""Time-optimal by default: known answers, TOPP-RA on the same path, limits sampled at 1 kHz."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from planner.errors import PlannerError
from planner.feasibility import RELATIVE_TOLERANCE
from planner.pipeline import PlannedTrajectory, PlanOptions, plan_strokes
from planner.qp_structure import SPEED_POLYTOPE_APOTHEM
from planner.timeopt_reference import line_min_time_s, toppra_duration_s

OPTIMAL_RATIO = 1.25
"""Default plans fly within this factor of the time-optimal duration of their path."""
HAVE_TOPPRA = importlib.util.find_spec("toppra") is not None
needs_toppra = pytest.mark.skipif(
    not HAVE_TOPPRA, reason="toppra (the dev extra) is not installed: no time-optimal reference"
)
L_TICK = [
    np.array([[0.0, 0.6], [0.0, 0.3], [0.0, 0.0], [0.2, 0.0], [0.4, 0.0]]) - 0.3,
    np.array([[0.55, 0.05], [0.6, 0.0], [0.75, 0.2]]) - 0.3,
]


def _within_limits_at_1khz(traj: PlannedTrajectory) -> tuple[float, float]:
    """Largest share of its bound of |a_i| and of |v| over samples at 1 kHz; asserts <= 1."""
    _, v, a, _ = traj.evaluate(traj.sample_times(1000.0))
    lower, upper = traj.limits.accel_bounds_mps2()
    share_a = float(np.max(np.maximum(a / np.asarray(upper), a / np.asarray(lower))))
    share_v = float(np.max(np.linalg.norm(v, axis=1))) / traj.limits.v_max_mps
    # acceleration bounds are exact in the QP; the speed polytope lies inside the v_max ball
    assert share_a <= 1.0 + RELATIVE_TOLERANCE
    assert share_v <= 1.0 + RELATIVE_TOLERANCE
    return share_a, share_v


def _binding_share(traj: PlannedTrajectory) -> float:
    """Share of the binding limit as the QP imposes it (speed: the inscribed polytope)."""
    share_a, share_v = _within_limits_at_1khz(traj)
    return max(share_a, share_v / SPEED_POLYTOPE_APOTHEM)


def _line(length_m: float, axis: int) -> list[np.ndarray]:
    end = np.zeros(2)
    end[axis] = length_m
    return [np.array([-0.5 * end, 0.5 * end])]


@pytest.mark.parametrize(("length_m", "axis"), [(0.3, 0), (0.6, 1), (1.0, 0)])
def test_a_straight_line_flies_within_the_bound_of_bang_coast_bang(
    length_m: float, axis: int
) -> None:
    options = PlanOptions(clearance_m=0.0)  # no hops: the path is the line itself
    traj = plan_strokes(_line(length_m, axis), options)
    lower, upper = traj.limits.accel_bounds_mps2()
    a_axis = min(-lower[axis], upper[axis])
    optimal = line_min_time_s(length_m, a_axis, traj.limits.v_max_mps)
    assert optimal <= traj.duration_s <= OPTIMAL_RATIO * optimal
    assert _binding_share(traj) > 0.97  # the binding limit is reached, not merely respected


@needs_toppra
def test_toppra_reference_reproduces_the_known_answer_of_a_line() -> None:
    traj = plan_strokes(_line(0.6, 0), PlanOptions(clearance_m=0.0))
    lower, upper = traj.limits.accel_bounds_mps2()
    reference = toppra_duration_s(traj.spline, lower, upper, traj.limits.v_max_mps)
    assert reference == pytest.approx(line_min_time_s(0.6, 0.8, 0.5), rel=5e-3)


def test_the_report_states_the_dense_check_and_agrees_with_it() -> None:
    traj = plan_strokes(L_TICK, PlanOptions())
    rep = traj.feasibility
    assert rep.sampled_rate_hz >= 1000.0
    share_a, share_v = _within_limits_at_1khz(traj)
    assert rep.sampled_accel_share == pytest.approx(share_a, abs=2e-3)
    assert rep.sampled_speed_share == pytest.approx(share_v, abs=2e-3)
    assert rep.to_json_dict()["sampled_accel_share"] <= 1.0 + RELATIVE_TOLERANCE
    assert rep.feasible


def test_default_pace_is_much_faster_than_the_nominal_one_and_as_accurate() -> None:
    fast = plan_strokes(L_TICK, PlanOptions())
    gentle = plan_strokes(L_TICK, PlanOptions(pace="nominal"))
    assert fast.duration_s < 0.75 * gentle.duration_s
    assert _binding_share(fast) > 0.97  # at the binding limit
    assert _binding_share(gentle) < 0.9  # below it everywhere
    assert fast.feasibility.path_error_max_m <= 0.025


def test_an_unknown_pace_is_refused_by_name() -> None:
    with pytest.raises(PlannerError, match="unknown pace 'fast'") as info:
        PlanOptions(pace="fast")
    assert info.value.field == "pace"


_POINT = st.tuples(st.floats(-0.45, 0.45), st.floats(-0.45, 0.45))
_STROKES = st.lists(st.lists(_POINT, min_size=2, max_size=6), min_size=1, max_size=3)


def _plan_random(strokes: list[list[tuple[float, float]]]) -> PlannedTrajectory | None:
    arrays = [np.array(s) for s in strokes]
    ink_m = sum(float(np.sum(np.linalg.norm(np.diff(a, axis=0), axis=1))) for a in arrays)
    # A drawing with less ink is mostly its two vertical hops: short rest-to-rest moves, where a
    # minimum-jerk profile needs up to 1.26x the bang-bang time (see the report's figures).
    assume(ink_m >= 0.3 and all(np.ptp(a, axis=0).max() > 1e-3 for a in arrays))
    try:
        return plan_strokes(arrays, PlanOptions())
    except PlannerError as exc:  # zero-length strokes after merging repeats
        assert "distinct" in str(exc)
        return None


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(strokes=_STROKES)
def test_random_polylines_keep_the_limits_when_sampled_at_1khz(
    strokes: list[list[tuple[float, float]]],
) -> None:
    traj = _plan_random(strokes)
    if traj is not None:
        _within_limits_at_1khz(traj)
        assert traj.feasibility.path_error_max_m <= 0.025


@needs_toppra
@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(strokes=_STROKES)
def test_random_polylines_fly_within_the_bound_of_toppra_on_the_same_path(
    strokes: list[list[tuple[float, float]]],
) -> None:
    traj = _plan_random(strokes)
    if traj is not None:
        lower, upper = traj.limits.accel_bounds_mps2()
        optimal = toppra_duration_s(traj.spline, lower, upper, traj.limits.v_max_mps)
        assert optimal <= traj.duration_s <= OPTIMAL_RATIO * optimal


@needs_toppra
def test_a_chinese_character_flies_near_time_optimal() -> None:
    from planner.glyphs import fit_to_area, text_glyph

    strokes = fit_to_area(text_glyph("永"), width_m=1.0, height_m=1.0, margin_m=0.05).strokes
    traj = plan_strokes(strokes, PlanOptions())
    lower, upper = traj.limits.accel_bounds_mps2()
    optimal = toppra_duration_s(traj.spline, lower, upper, traj.limits.v_max_mps)
    assert traj.duration_s <= OPTIMAL_RATIO * optimal
    assert traj.duration_s < 25.0  # 38 s at the nominal pace

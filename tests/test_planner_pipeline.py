"""plan_strokes end to end: pen up/down, rest-to-rest, limits, report, errors (properties)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from planner.board import BoardFrame
from planner.errors import InfeasibleTrajectoryError, PlannerError
from planner.limits import GRAVITY_MPS2, VehicleLimits
from planner.pipeline import PlanOptions, plan_strokes
from planner.samples import TrajectorySamples

L_TICK = [
    np.array([[0.0, 0.6], [0.0, 0.3], [0.0, 0.0], [0.2, 0.0], [0.4, 0.0]]) - 0.3,
    np.array([[0.55, 0.05], [0.6, 0.0], [0.75, 0.2]]) - 0.3,
]
BOARD = BoardFrame(center_m_enu=(2.0, -1.0, 0.75), yaw_rad=0.3)
OPTIONS = PlanOptions(board=BOARD)


@pytest.fixture(scope="module")
def planned() -> object:
    return plan_strokes(L_TICK, OPTIONS)


def test_rest_to_rest_above_first_and_last_stroke(planned: object) -> None:
    traj = planned
    t_end = np.array([0.0, traj.duration_s])
    p, v, a, _ = traj.evaluate(t_end)
    np.testing.assert_allclose(v, 0.0, atol=1e-9)
    np.testing.assert_allclose(a, 0.0, atol=1e-9)
    above = OPTIONS.write_height_m + OPTIONS.clearance_m
    start = BOARD.to_world(L_TICK[0][:1])[0] + [0, 0, above]
    end = BOARD.to_world(L_TICK[1][-1:])[0] + [0, 0, above]
    np.testing.assert_allclose(p, [start, end], atol=1e-9)


def test_pen_down_only_at_writing_height_during_strokes(planned: object) -> None:
    traj = planned
    samples = traj.sample(100.0)
    assert isinstance(samples, TrajectorySamples)
    steps = np.diff(samples.t_s)  # 0, 10 ms, 20 ms, ... and the end (its mean rate varies)
    np.testing.assert_allclose(steps[:-1], 0.01, rtol=1e-9)
    assert 0.0 < steps[-1] <= 0.01 + 1e-12 and samples.t_s[-1] == traj.duration_s
    assert not samples.pen_down[0] and not samples.pen_down[-1]
    height = BOARD.height_above_m(samples.position_m_enu)
    write_m = OPTIONS.write_height_m
    assert np.all(height[samples.pen_down] <= write_m + 0.005 + 1e-12)
    assert np.min(height) >= write_m - 1e-6  # never below writing height (QP floor)
    # two separate pen-down runs, one per stroke
    runs = np.count_nonzero(np.diff(samples.pen_down.astype(int)) == 1)
    assert runs == 2
    # while writing the brush traces the strokes: board-plane distance to the input polylines
    xy = BOARD.to_board(samples.position_m_enu[samples.pen_down])
    deviation = _distance_to_polylines(xy, L_TICK).max()
    assert deviation < 0.01
    assert traj.feasibility.path_error_max_m == pytest.approx(deviation, abs=2e-3)


def _distance_to_polylines(xy: np.ndarray, strokes: list[np.ndarray]) -> np.ndarray:
    best = np.full(xy.shape[0], np.inf)
    for s in strokes:
        for a, b in itertools.pairwise(s):
            ab = b - a
            u = np.clip((xy - a) @ ab / (ab @ ab), 0, 1)
            best = np.minimum(best, np.linalg.norm(xy - (a + u[:, None] * ab), axis=1))
    return best


def test_report_is_consistent_with_dense_samples(planned: object) -> None:
    traj = planned
    t = np.linspace(0.0, traj.duration_s, 40001)
    _, v, a, j = traj.evaluate(t)
    rep = traj.feasibility
    assert rep.feasible
    np.testing.assert_allclose(np.max(np.abs(a), axis=0), rep.peak_accel_mps2, rtol=1e-3)
    assert np.max(np.linalg.norm(v, axis=1)) == pytest.approx(rep.peak_speed_mps, rel=1e-4)
    thrust = traj.limits.mass_kg * np.linalg.norm(a + np.array([0, 0, GRAVITY_MPS2]), axis=1)
    assert np.max(thrust) == pytest.approx(rep.peak_thrust_n, rel=1e-4)
    assert np.min(thrust) == pytest.approx(rep.min_thrust_n, rel=1e-4)
    assert rep.fit_error_max_m < 0.02
    assert len(rep.fit_error_max_per_stroke_m) == 2
    assert rep.body_rate_bound_radps < rep.body_rate_max_radps
    # eq. (15) bound from the samples
    omega2 = np.sum(np.max(j**2, axis=0)) / np.sum(
        np.min((a + np.array([0, 0, GRAVITY_MPS2])) ** 2, axis=0)
    )
    assert rep.body_rate_bound_radps == pytest.approx(np.sqrt(omega2), rel=1e-2)


def test_json_has_the_agreed_fields(planned: object) -> None:
    doc = planned.to_json_dict()
    for key in ("duration_s", "samples", "limits", "timing_ms", "feasibility", "turning_points"):
        assert key in doc
    samples = TrajectorySamples.from_json_dict(doc["samples"])
    assert samples.position_m_enu.shape[1] == 3
    assert doc["limits"]["a_max"] == [0.8, 0.8, 0.5]
    assert doc["turning_points"][0] == [[-0.3, 0.3], [-0.3, -0.3], [0.1, -0.3]]


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    strokes=st.lists(
        st.lists(st.tuples(st.floats(-0.45, 0.45), st.floats(-0.45, 0.45)), min_size=2, max_size=6),
        min_size=1,
        max_size=3,
    ),
    total=st.sampled_from([None, "loose"]),
)
def test_random_strokes_give_smooth_limited_rest_to_rest_paths(
    strokes: list[list[tuple[float, float]]], total: str | None
) -> None:
    arrays = [np.array(s) for s in strokes]
    if any(np.all(np.ptp(a, axis=0) < 1e-3) for a in arrays):
        return  # a stroke without two distinct points is rejected, tested elsewhere
    options = PlanOptions(split_threshold_m=0.01)
    try:
        traj = plan_strokes(arrays, options)
    except PlannerError as exc:  # zero-length after merging repeats
        assert "distinct" in str(exc)
        return
    if total == "loose":
        traj = plan_strokes(arrays, PlanOptions(total_time_s=1.3 * traj.duration_s))
    spline = traj.spline
    # continuity up to acceleration across every knot
    knots = spline.knot_times_s()[1:-1]
    eps = 1e-9
    for order in (0, 1, 2):
        left = spline.evaluate(knots - eps, order)
        right = spline.evaluate(knots + eps, order)
        np.testing.assert_allclose(left, right, atol=1e-5)
    t = np.linspace(0.0, traj.duration_s, 20001)
    _, v, a, _ = traj.evaluate(t)
    lim = traj.limits
    assert np.all(np.abs(a) <= np.array(lim.a_max_mps2) + 1e-6)
    assert np.max(np.linalg.norm(v, axis=1)) <= lim.v_max_mps + 1e-6
    np.testing.assert_allclose(v[[0, -1]], 0.0, atol=1e-9)
    np.testing.assert_allclose(a[[0, -1]], 0.0, atol=1e-9)


def test_too_short_total_time_names_the_limit() -> None:
    with pytest.raises(InfeasibleTrajectoryError) as info:
        plan_strokes(L_TICK, PlanOptions(total_time_s=3.0))
    assert info.value.limit in ("a_max", "v_max")
    assert info.value.axis in ("x", "y", "z", None)
    assert 0.0 <= info.value.t_s <= 3.0


def test_closed_form_method_raises_instead_of_violating() -> None:
    limits = VehicleLimits(a_max_mps2=(0.8, 0.8, 0.5), v_max_mps=0.5)
    options = PlanOptions(
        limits=limits, method="closed-form", total_time_s=7.0, resegment=False, fit_tolerance_m=None
    )
    with pytest.raises(InfeasibleTrajectoryError) as info:
        plan_strokes(L_TICK, options)
    assert info.value.limit in ("a_max", "v_max")
    assert abs(info.value.value) > abs(info.value.bound)


def test_body_rate_limit_is_enforced() -> None:
    limits = VehicleLimits(body_rate_max_radps=1e-3)
    with pytest.raises(InfeasibleTrajectoryError) as info:
        plan_strokes(L_TICK, PlanOptions(limits=limits))
    assert info.value.limit == "body_rate"


def test_bad_strokes_name_stroke_and_point() -> None:
    bad = [L_TICK[0], np.array([[0.0, 0.0], [np.nan, 1.0]])]
    with pytest.raises(PlannerError) as info:
        plan_strokes(bad, PlanOptions())
    assert (info.value.stroke_index, info.value.point_index) == (1, 1)
    with pytest.raises(PlannerError) as info:
        plan_strokes([np.array([[0.1, 0.1], [0.1, 0.1]])], PlanOptions())
    assert info.value.stroke_index == 0


def test_limits_validation() -> None:
    with pytest.raises(PlannerError):
        VehicleLimits(thrust_max_n=5.0)  # cannot hover 1 kg
    lower, upper = VehicleLimits().accel_bounds_mps2()
    assert lower == (-0.8, -0.8, -0.5) and upper == (0.8, 0.8, 0.5)


def test_resegmentation_lowers_cost_in_the_pipeline() -> None:
    base = plan_strokes(L_TICK, PlanOptions(resegment=False, total_time_s=14.0))
    better = plan_strokes(L_TICK, PlanOptions(resegment=True, total_time_s=14.0))
    assert better.info["cost_final"] <= better.info["cost_initial"]
    assert better.info["cost"] <= base.info["cost"] * (1 + 1e-9)
    assert better.duration_s == pytest.approx(14.0)


def test_board_frame_round_trip_and_yaw() -> None:
    xy = np.array([[0.1, 0.0], [0.0, 0.2], [-0.3, 0.4]])
    world = BOARD.to_world(xy)
    np.testing.assert_allclose(world[:, 2], 0.75)
    np.testing.assert_allclose(BOARD.to_board(world), xy, atol=1e-12)
    east = BoardFrame((0.0, 0.0, 0.0), yaw_rad=np.pi / 2).to_world(np.array([[1.0, 0.0]]))
    np.testing.assert_allclose(east, [[0.0, 1.0, 0.0]], atol=1e-12)  # board x points north


def test_plot_has_path_and_limit_panels(planned: object) -> None:
    from matplotlib.figure import Figure

    from planner.plots import plot_trajectory

    fig = plot_trajectory(planned, L_TICK)
    assert isinstance(fig, Figure)
    axes = fig.get_axes()
    assert len(axes) == 4
    labels = {line.get_label() for line in axes[0].get_lines()}
    assert {"input points", "pen down", "pen up", "turning points"} <= labels
    horizontal = [ln for ln in axes[3].get_lines() if len(ln.get_ydata()) == 2]
    assert {round(float(ln.get_ydata()[0]), 6) for ln in horizontal} == {0.8, -0.8, 0.5, -0.5}
    speed_lines = [ln for ln in axes[2].get_lines() if ln.get_label() == "v_max"]
    assert float(speed_lines[0].get_ydata()[0]) == 0.5


def test_oversized_input_is_refused_quickly_and_named() -> None:
    rng = np.random.default_rng(0)
    with pytest.raises(PlannerError, match="20000 points") as million:
        plan_strokes([rng.random((1_000_000, 2)) * 0.5], PlanOptions())
    assert million.value.field == "strokes" and million.value.stroke_index == 0
    with pytest.raises(PlannerError, match="strokes; at most 200"):
        plan_strokes([np.array([[0.0, 0.0], [0.1, 0.0]])] * 201, PlanOptions())
    # Few enough points, but a scribble with far more turning points than one job can write.
    with pytest.raises(PlannerError, match="turning points; at most 3000"):
        plan_strokes([rng.random((15_000, 2)) * 0.5], PlanOptions())


def test_consecutive_duplicate_points_plan_like_the_deduplicated_stroke() -> None:
    stroke = np.array([[0.0, 0.0], [0.2, 0.0], [0.2, 0.2]])
    doubled = np.repeat(stroke, 2, axis=0)
    plain = plan_strokes([stroke], PlanOptions())
    repeated = plan_strokes([doubled], PlanOptions())
    assert repeated.duration_s == pytest.approx(plain.duration_s, rel=1e-6)

"""The pen-down path stays on the strokes: vertical hops at stroke ends, and the safety net."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from planner.board import BoardFrame
from planner.errors import InfeasibleTrajectoryError
from planner.glyphs import fit_to_area, has_glyph, text_glyph
from planner.minjerk import EndState, FitProblem
from planner.pipeline import PlannedTrajectory, PlanOptions, plan_strokes
from planner.refine import REFINE_TARGET, StrokeErrors, tighten
from planner.waypoints import KIND_HOP, KIND_TURNING, build_path

L_TICK = [
    np.array([[0.0, 0.6], [0.0, 0.3], [0.0, 0.0], [0.2, 0.0], [0.4, 0.0]]) - 0.3,
    np.array([[0.55, 0.05], [0.6, 0.0], [0.75, 0.2]]) - 0.3,
]
# Three parallel down-strokes: the travel to the next stroke starts in the direction the brush
# was moving, so a brush that reaches a stroke end at speed slides on past it.
BARS = [np.array([[x, 0.3], [x, -0.3]]) for x in (-0.45, 0.0, 0.45)]
BOARD = BoardFrame((0.0, 0.0, 0.0))
WRITE_HEIGHT_M = 0.335  # as in the shows


def _gb2312_level1(index: int) -> str:
    return bytes([0xB0 + index // 94, 0xA1 + index % 94]).decode("gb2312")


def _distance_to_polyline(xy: np.ndarray, line: np.ndarray) -> np.ndarray:
    best = np.full(xy.shape[0], np.inf)
    for a, b in itertools.pairwise(line):
        ab = b - a
        u = np.clip((xy - a) @ ab / (ab @ ab), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(xy - (a + u[:, None] * ab), axis=1))
    return best


def _worst_pen_down_distance(traj: PlannedTrajectory, strokes: tuple[np.ndarray, ...]) -> float:
    """Independent of the report: pen-down samples against the INPUT stroke polylines."""
    samples = traj.sample(100.0)
    worst = 0.0
    for (t0, t1), stroke in zip(traj.stroke_intervals_s, strokes, strict=True):
        mask = samples.pen_down & (samples.t_s >= t0) & (samples.t_s <= t1)
        xy = traj.board.to_board(samples.position_m_enu[mask])
        worst = max(worst, float(np.max(_distance_to_polyline(xy, stroke), initial=0.0)))
    return worst


@pytest.mark.slow
@pytest.mark.parametrize("clearance_m", [0.05, 0.08])
def test_gb2312_sample_at_one_metre_plans_within_tolerance(clearance_m: float) -> None:
    chars = [c for c in map(_gb2312_level1, range(0, 3755, 60)) if has_glyph(c)]
    assert len(chars) >= 60
    options = PlanOptions(clearance_m=clearance_m, board=BOARD, write_height_m=WRITE_HEIGHT_M)
    tolerance = options.fit_tolerance_m
    assert tolerance is not None
    for char in chars:
        strokes = fit_to_area(text_glyph(char), width_m=1.0, height_m=1.0).strokes
        traj = plan_strokes(strokes, options)  # raises if any limit or the tolerance is broken
        rep = traj.feasibility
        assert rep.feasible, char
        assert max(rep.path_error_max_m, rep.fit_error_max_m) <= tolerance, char
        # the input points lie within the split threshold of the turning-point polylines
        assert _worst_pen_down_distance(traj, strokes) <= tolerance + 0.011, char


def test_clearance_zero_is_accepted_and_the_brush_never_lifts() -> None:
    traj = plan_strokes(
        L_TICK, PlanOptions(clearance_m=0.0, board=BOARD, write_height_m=WRITE_HEIGHT_M)
    )
    t = traj.sample_times(100.0)
    z = traj.evaluate(t)[0][:, 2]
    np.testing.assert_allclose(z, traj.write_z_m, atol=1e-9)
    assert traj.feasibility.feasible
    assert traj.feasibility.path_error_max_m <= 0.025
    assert _worst_pen_down_distance(traj, tuple(L_TICK)) <= 0.025 + 0.011


def test_every_hop_holds_the_brush_above_the_stroke_end() -> None:
    settings = PlanOptions(
        clearance_m=0.05, board=BOARD, write_height_m=WRITE_HEIGHT_M
    ).path_settings()
    path = build_path(BARS, BOARD, settings)
    for k, (approach, lift) in enumerate(path.pen_windows):
        first, last = path.stroke_ranges[k]
        for above, end in ((range(approach + 1, first), first), (range(last + 1, lift), last)):
            hops = path.points_m_enu[list(above)]
            assert hops.shape[0] >= 2  # a hop of 5 cm (< the densify spacing) still gets points
            assert np.all(path.kinds[list(above)] == KIND_HOP)
            np.testing.assert_allclose(hops[:, :2] - path.points_m_enu[end, :2], 0.0, atol=1e-12)
            assert np.all(hops[:, 2] > path.write_z_m)
            assert np.all(hops[:, 2] < path.write_z_m + 0.05)
        assert path.kinds[first] == path.kinds[last] == KIND_TURNING


@pytest.mark.parametrize("clearance_m", [0.02, 0.05, 0.08])
def test_the_brush_does_not_slide_past_stroke_ends_without_the_safety_net(
    clearance_m: float,
) -> None:
    # Before the hop points a 5 cm hop let the brush smear 28 mm past the bars' ends.
    options = PlanOptions(
        clearance_m=clearance_m, fit_tolerance_m=None, board=BOARD, write_height_m=WRITE_HEIGHT_M
    )
    traj = plan_strokes(BARS, options)
    assert traj.info["refine_rounds"] == 0
    assert traj.feasibility.path_error_max_m < 0.008
    assert _worst_pen_down_distance(traj, tuple(BARS)) < 0.008


@pytest.mark.parametrize("pace", ["nominal", "limits"])
def test_a_heavy_jerk_weight_is_brought_within_tolerance(pace: str) -> None:
    loose = plan_strokes(L_TICK, PlanOptions(jerk_weight_s5=1e-2, fit_tolerance_m=None, pace=pace))
    assert max(loose.feasibility.fit_error_max_m, loose.feasibility.path_error_max_m) > 0.015
    tight = plan_strokes(L_TICK, PlanOptions(jerk_weight_s5=1e-2, fit_tolerance_m=0.01, pace=pace))
    if pace == "nominal":  # the safety net does it (at pace "limits" the re-timing does)
        assert tight.info["refine_rounds"] >= 1
    assert max(tight.feasibility.fit_error_max_m, tight.feasibility.path_error_max_m) <= 0.01
    assert _worst_pen_down_distance(tight, tuple(L_TICK)) <= 0.01 + 1e-3
    assert tight.feasibility.feasible


def test_refinement_keeps_a_fixed_total_time() -> None:
    loose = PlanOptions(jerk_weight_s5=1e-2, fit_tolerance_m=None, total_time_s=16.0)
    untouched = plan_strokes(L_TICK, loose).feasibility
    assert max(untouched.fit_error_max_m, untouched.path_error_max_m) > 0.012
    options = PlanOptions(jerk_weight_s5=1e-2, fit_tolerance_m=0.012, total_time_s=16.0)
    traj = plan_strokes(L_TICK, options)
    assert traj.info["refine_rounds"] >= 1
    assert traj.duration_s == pytest.approx(16.0, rel=1e-12)
    assert max(traj.feasibility.fit_error_max_m, traj.feasibility.path_error_max_m) <= 0.012
    assert traj.feasibility.feasible


def test_too_little_time_names_the_limit_that_pulls_the_path_off() -> None:
    with pytest.raises(InfeasibleTrajectoryError) as info:
        plan_strokes(L_TICK, PlanOptions(total_time_s=5.0, clearance_m=0.05))
    err = info.value
    assert err.limit == "a_max"
    assert err.axis in ("x", "y", "z")
    assert abs(err.value) > abs(err.bound)
    assert err.stroke_index in (0, 1)
    assert "strays" in str(err)


def test_an_unreachable_tolerance_is_reported_as_fit_error_with_the_stroke() -> None:
    with pytest.raises(InfeasibleTrajectoryError) as info:
        plan_strokes(L_TICK, PlanOptions(fit_tolerance_m=2e-4))
    err = info.value
    assert err.limit == "fit_error"
    assert err.value > err.bound == pytest.approx(2e-4)
    assert err.stroke_index in (0, 1)
    assert err.t_s >= 0.0


def _problem(n: int = 9) -> FitProblem:
    points = np.column_stack([np.linspace(0.0, 1.0, n), np.zeros(n), np.zeros(n)])
    return FitProblem(
        times_s=np.arange(n, dtype=np.float64),
        points_m=points,
        weights=np.ones(n),
        n_spans=8,
        duration_s=float(n - 1),
        jerk_weight_s5=1e-4,
        start=EndState(points[0]),
        end=EndState(points[-1]),
    )


def _errors(spots: tuple[tuple[float, float], ...]) -> StrokeErrors:
    worst = max(spots)
    return StrokeErrors(path_m=(worst[0],), turning_m=(0.0,), worst_t_s=(worst[1],), spots=spots)


@pytest.mark.parametrize("fixed_total", [False, True])
def test_tighten_acts_only_around_spots_above_target(fixed_total: bool) -> None:
    problem = _problem()
    target = REFINE_TARGET * 0.025
    assert (
        tighten(
            problem, _errors(((0.001, 4.5),)), target, fixed_total=fixed_total, min_duration_s=0.05
        )
        is None
    )
    change = tighten(
        problem,
        _errors(((0.001, 1.0), (0.03, 4.5))),
        target,
        fixed_total=fixed_total,
        min_duration_s=0.05,
    )
    assert change is not None
    weights, durations = change
    heavier = np.flatnonzero(weights > 1.0)
    assert heavier.min() >= 3 and heavier.max() <= 6 and 4 in heavier and 5 in heavier
    assert durations[4] > 1.0  # the segment holding the spot takes longer
    if fixed_total:
        assert float(np.sum(durations)) == pytest.approx(problem.duration_s, rel=1e-12)
        assert np.all(durations >= 0.05)
        assert durations[0] < 1.0
    else:
        assert durations[0] == 1.0

"""The wall writer's plan stays on the letter (issue 33): corridors around the strokes' parabolas
(our extension of eq. 7), long and sharp strokes in pieces, and the metrics that measure it."""

from __future__ import annotations

import dataclasses
import itertools
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from module_by_path import load_module

from planner.errors import PlannerError
from planner.glyphs.layout import fit_to_area
from planner.glyphs.text import text_glyph
from vehicles.hexarotor_sponge.corridor import corridor_rows, segment_times_s, turns_rad
from vehicles.hexarotor_sponge.fidelity import distance_to_strokes_m
from vehicles.hexarotor_sponge.kind import WallSettings, with_default_widths
from vehicles.hexarotor_sponge.limits import Limits
from vehicles.hexarotor_sponge.long_periods import split_long
from vehicles.hexarotor_sponge.metrics import as_flown, plan_fidelity, score_writing
from vehicles.hexarotor_sponge.nlp import solve_period
from vehicles.hexarotor_sponge.parabolas import FIT_TOLERANCE_M, refined
from vehicles.hexarotor_sponge.params import HexarotorParams
from vehicles.hexarotor_sponge.plan import PlanSettings, plan_writing
from vehicles.hexarotor_sponge.steps import steps_per_segment
from vehicles.hexarotor_sponge.waypoints import Period
from vehicles.kind import StrokeInput, WritingPlan
from vehicles.surface import Surface

SURFACE = Surface.of("vertical", (0.0, 3.0, 2.0), 0.0)
WIDTH_M = WallSettings().plan.default_width_m


def _letter(text: str, size_m: float = 1.0) -> list[StrokeInput]:
    glyph = fit_to_area(text_glyph(text), width_m=size_m, height_m=size_m)
    raw = [StrokeInput(np.asarray(s, dtype=np.float64)) for s in glyph.strokes]
    return with_default_widths(raw, WallSettings())


def _plan(strokes: list[StrokeInput], limits: Limits | None = None) -> WritingPlan:
    settings = PlanSettings() if limits is None else PlanSettings(limits=limits)
    return plan_writing(strokes, SURFACE, settings, solve=solve_period)


def test_distance_to_strokes_known_answers() -> None:
    square = StrokeInput(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]))
    dot_line = StrokeInput(np.array([[3.0, 0.0], [3.0, 0.0]]))
    points = np.array([[0.5, 0.2], [1.3, 0.5], [-0.3, -0.4], [2.0, 0.0], [3.0, 0.5]])
    d = distance_to_strokes_m(points, [square, dot_line])
    assert d == pytest.approx([0.2, 0.3, 0.5, 1.0, 0.5])


def test_a_parabolas_sagitta_is_found_exactly() -> None:
    t = np.linspace(0.0, 1.0, 41)
    xy = np.column_stack([0.2 * t, 0.004 * 4.0 * t * (1.0 - t)])  # 4 mm to the left of the chord
    kept, sagittas = refined(xy, np.array([0, 40]))
    assert kept.tolist() == [0, 40]
    assert sagittas == pytest.approx([0.004], rel=1e-3)


@settings(max_examples=25, deadline=None)
@given(
    radius_m=st.floats(0.02, 0.5),
    sweep_rad=st.floats(0.5, 6.0),
    points=st.integers(20, 200),
)
def test_refined_parabolas_stay_within_their_tolerance_of_an_arc(
    radius_m: float, sweep_rad: float, points: int
) -> None:
    """However much of a circle a stroke sweeps, every chord's parabola ends within the fit
    tolerance of the stroke's points between its waypoints."""
    theta = np.linspace(0.0, sweep_rad, points)
    xy = radius_m * np.column_stack([np.cos(theta), np.sin(theta)])
    kept, sagittas = refined(xy, np.array([0, points - 1]))
    for (a, b), q in zip(itertools.pairwise(kept), sagittas, strict=True):
        chord = xy[b] - xy[a]
        length = float(np.linalg.norm(chord))
        u = chord / length
        rel = xy[a : b + 1] - xy[a]
        s = np.clip(rel @ u / length, 0.0, 1.0)
        across = rel @ np.array([-u[1], u[0]])
        assert np.abs(across - 4.0 * q * s * (1.0 - s)).max() <= FIT_TOLERANCE_M + 1e-9


def _contact_period(xy: np.ndarray, sagittas: np.ndarray) -> Period:
    points = np.column_stack([xy, np.zeros(len(xy))])
    points = np.vstack([points[:1], points, points[-1:]])
    force = np.concatenate([[0.0], np.full(len(xy), 2.0), [0.0]])
    return Period(True, points, force, 0, "writing it", np.concatenate([[0.0], sagittas, [0.0]]))


def test_corridor_rows_hold_the_waypoints_and_the_parabola() -> None:
    """A node at a waypoint, and one on the parabola halfway along a chord, read the middle of
    their corridor across and lie between the chord's ends along it."""
    xy = np.array([[0.0, 0.0], [0.1, 0.0], [0.1, 0.1]])
    period = _contact_period(xy, np.array([0.002, 0.0]))
    nodes = np.array([0, 2, 6, 10, 12])
    rows, lower, upper = corridor_rows(period, nodes, 5e-4)
    middle = np.array([0.05, 0.002])  # halfway along the first chord, on its parabola
    for k, p in ((2, xy[0]), (4, middle), (6, xy[1]), (8, np.array([0.1, 0.05]))):
        normal, direction, start, length, bend = rows[k, 0:2], rows[k, 2:4], *rows[k, 4:7]
        u = direction @ p - start
        across = normal @ p - bend * u * (length - u)
        assert across == pytest.approx(0.5 * (lower[k, 0] + upper[k, 0]), abs=1e-12)
        assert lower[k, 1] - 1e-12 <= direction @ p <= upper[k, 1] + 1e-12
    assert upper[4, 0] - lower[4, 0] == pytest.approx(1e-3)


def test_a_sharp_turn_gets_time_to_stop_and_a_straight_run_does_not() -> None:
    """The corner's speed limit shows in the chords' times: a right angle slows the pen to all
    but a stop, a straight continuation does not."""
    limits = Limits()
    corner = _contact_period(np.array([[0.0, 0.0], [0.2, 0.0], [0.2, 0.2]]), np.zeros(2))
    straight = _contact_period(np.array([[0.0, 0.0], [0.2, 0.0], [0.4, 0.0]]), np.zeros(2))
    times = [segment_times_s(p, 5e-4, 0.2, 0.2) for p in (corner, straight)]
    assert np.degrees(turns_rad(corner)[1]) == pytest.approx(90.0)
    assert times[0][1] > 1.2 * times[1][1]
    assert sum(steps_per_segment(corner, limits)) > sum(steps_per_segment(straight, limits))


def test_sharp_turns_and_long_strokes_are_split_into_pieces_that_keep_the_stroke() -> None:
    xy = np.column_stack([np.linspace(0.0, 1.0, 41), 0.05 * np.sin(np.linspace(0.0, 9.0, 41))])
    xy = np.vstack([xy, [[1.0, 0.5]]])  # a right angle at the end
    period = _contact_period(xy, np.zeros(len(xy) - 1))
    pieces = split_long([period], Limits(), 40)
    assert len(pieces) >= 3
    assert all(sum(steps_per_segment(p, Limits())) <= 40 for p in pieces[:-1])
    joined = np.vstack([pieces[0].points_m] + [p.points_m[1:] for p in pieces[1:]])
    assert np.array_equal(joined, period.points_m)
    assert np.array_equal(pieces[-2].points_m[-1, :2], xy[-2])  # cut at the right angle
    whole = split_long([period], Limits(corridor_m=None), 10_000)
    assert len(whole) == 1 and whole[0] is period


@pytest.mark.slow
@pytest.mark.parametrize("text", ["8", "永", "R", "&"])
def test_a_1_m_letters_plan_stays_on_its_strokes(text: str) -> None:
    """Issue 33's targets for the plan alone: within 5 mm of the strokes, IoU >= 0.90 (the
    paper's eq. 7 was 15.7 mm and 0.483 on "8", 29.6 mm and 0.601 on 永)."""
    fidelity = plan_fidelity(_plan(_letter(text)), WIDTH_M)
    assert fidelity["plan_max_to_strokes_m"] <= 2.5e-3
    assert fidelity["plan_iou"] >= 0.92


@pytest.mark.slow
def test_the_papers_formulation_is_kept_and_leaves_the_strokes() -> None:
    """The setting ``corridor_m=None`` is the paper's eq. 7: on the 1 m "8" its plan swings
    centimetres off the strokes between waypoints (what the corridors fix)."""
    fidelity = plan_fidelity(_plan(_letter("8"), Limits(corridor_m=None)), WIDTH_M)
    assert fidelity["plan_max_to_strokes_m"] > 10e-3
    assert fidelity["plan_iou"] < 0.6


def _spiral() -> list[StrokeInput]:
    theta = np.linspace(0.0, 2.0 * np.pi * 5, 500)
    radius = 0.015 + 0.5 * theta / theta[-1]
    xy = np.column_stack([radius * np.cos(theta), radius * np.sin(theta)])
    return with_default_widths([StrokeInput(xy)], WallSettings())


def _cursive_run() -> list[StrokeInput]:
    t = np.linspace(0.0, 2.0 * np.pi * 6, 360)
    xy = np.column_stack([t / (2.0 * np.pi) - 0.25 * np.sin(t), -np.cos(t)]) / 6.0
    return with_default_widths([StrokeInput(xy)], WallSettings())


@pytest.mark.slow
@pytest.mark.parametrize("strokes", [_spiral(), _cursive_run()], ids=["spiral", "cursive"])
def test_spirals_and_long_cursive_strokes_plan_on_their_strokes(
    strokes: list[StrokeInput],
) -> None:
    """One stroke of five 1 m turns, and a 1 m run of six loops (the paper's planner: a_max
    exceeded x4.5, IPOPT out of iterations): planned, in pieces, within limits and on the
    stroke."""
    plan = _plan(strokes)
    report = plan.feasibility
    pieces = [p for p in report["periods"] if p["contact"]]
    assert len(pieces) > 1
    assert float(report["peak_acceleration_mps2"]) <= 0.2 * 1.01
    fidelity = plan_fidelity(plan, WIDTH_M)
    assert fidelity["plan_max_to_strokes_m"] <= 2.5e-3
    assert fidelity["plan_iou"] >= 0.92


@pytest.mark.slow
def test_metrics_report_fidelity_and_the_largest_error_while_writing() -> None:
    """The plan flown perfectly but for a 5 cm hover offset before writing and a 3 mm offset
    across one pen-down tick: ``max_error_m`` is the 3 mm, and the letter's distances say so."""
    plan = _plan(_letter("I", 0.3))
    flown = as_flown(plan)
    tip = flown.writing_point_m_enu.copy()
    tip[0] += 0.05 * SURFACE.normal_enu
    k = int(np.flatnonzero(flown.pen_down)[5])
    tip[k] += 0.003 * np.asarray(SURFACE.x_axis_enu)
    moved = dataclasses.replace(flown, writing_point_m_enu=tip)
    score = score_writing(plan, moved, HexarotorParams(), WIDTH_M)
    assert score.max_error_m == pytest.approx(0.003, abs=1e-9)
    assert score.extra["max_to_strokes_m"] == pytest.approx(0.003, abs=5e-4)
    assert score.extra["rmse_to_strokes_m"] < score.extra["max_to_strokes_m"]
    assert score.extra["plan_max_to_strokes_m"] < 1e-3


def test_the_reach_refusal_reads_in_millimetres_and_lets_rounding_through() -> None:
    reach = PlanSettings().reach_m
    edge = StrokeInput(np.array([[0.0, 0.0], [reach + 4e-4, 0.0]]))
    beyond = StrokeInput(np.array([[0.0, 0.0], [0.0, reach + 0.002]]))
    with pytest.raises(PlannerError) as info:
        plan_writing([edge, beyond], SURFACE, PlanSettings())
    assert str(info.value) == (
        "stroke 1, point 1: point is 1.502 m from the wall's writing centre, beyond the reach 1.5 m"
    )


@pytest.mark.slow
def test_the_benchmarks_peer_solves_the_planners_problem() -> None:
    """``wall_opti_peer`` (a fresh ``casadi.Opti`` per period) solves the same NLP as the cached
    planner (same steps, step-change cost, corridors, start, options): the same optimum."""
    root = Path(__file__).resolve().parents[1]
    peer = load_module("wall_opti_peer", root / "benchmarks" / "wall_opti_peer.py")
    xy = np.array([[0.0, 0.0], [0.06, 0.01], [0.1, 0.05]])
    strokes = with_default_widths([StrokeInput(xy)], WallSettings())
    settings = PlanSettings()
    ours = plan_writing(strokes, SURFACE, settings, solve=solve_period)
    theirs = plan_writing(strokes, SURFACE, settings, solve=peer.solve_period_opti)
    steps = [[p["steps"] for p in plan.feasibility["periods"]] for plan in (ours, theirs)]
    assert steps[0] == steps[1]
    assert theirs.duration_s == pytest.approx(ours.duration_s, rel=1e-3)
    gap = np.abs(theirs.samples.position_m_enu - ours.samples.position_m_enu).max()
    assert gap < 2e-4

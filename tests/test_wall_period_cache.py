"""Periods solved earlier reused for identical periods (``hexarotor_sponge.period_cache``)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from vehicles.hexarotor_sponge import period_cache
from vehicles.hexarotor_sponge.limits import Limits
from vehicles.hexarotor_sponge.nlp import PeriodSolution, PeriodStart, solve_period
from vehicles.hexarotor_sponge.params import HexarotorParams
from vehicles.hexarotor_sponge.period_cache import SolvedPeriods
from vehicles.hexarotor_sponge.plan import PlanSettings, plan_writing
from vehicles.hexarotor_sponge.waypoints import Period, periods_of
from vehicles.kind import StrokeInput
from vehicles.surface import Surface

SURFACE = Surface.of("vertical", (0.0, 3.0, 2.0), 0.0)
PARAMS = HexarotorParams()
ARRAYS = ("t_s", "p_m", "v_mps", "a_mps2", "force_n", "control_n")


def _corner_stroke() -> list[Period]:
    strokes = [StrokeInput(np.array([[0.0, 0.0], [0.08, 0.0], [0.08, 0.06]]))]
    forces = [np.array([2.0, 3.0, 2.5])]
    return periods_of(strokes, forces, start_m=np.array([0.0, 0.0, 0.06]), standoff_m=0.03)


def _same_bits(a: PeriodSolution, b: PeriodSolution) -> bool:
    return all(np.array_equal(getattr(a, k), getattr(b, k)) for k in ARRAYS)


@pytest.mark.slow
def test_a_period_elsewhere_on_the_wall_reuses_the_trajectory_bit_for_bit() -> None:
    """The same stroke shape moved along the wall is not solved again; its trajectory is the
    one a new solve gives, to the bit, and says it was reused with the first solve's IPOPT
    figures."""
    cache = SolvedPeriods()
    first = _corner_stroke()[1]
    moved = dataclasses.replace(first, points_m=first.points_m + np.array([0.31, -0.17, 0.0]))
    a = cache.solve(first, PARAMS, Limits())
    b = cache.solve(moved, PARAMS, Limits())
    assert (a.start, b.start) == (PeriodStart.COLD, PeriodStart.REUSED)
    assert cache.stats().hits == 1 and cache.stats().misses == 1
    assert _same_bits(b, solve_period(moved, PARAMS, Limits()))
    assert b.p_m[0] == pytest.approx([0.31, -0.17, 0.0], abs=1e-12)
    assert (b.status, b.iterations, b.ipopt_s) == (a.status, a.iterations, a.ipopt_s)
    assert b.iterations > 0


@pytest.mark.slow
def test_other_forces_limits_or_vehicle_are_solved_anew() -> None:
    """Only an identical period in its own frame, vehicle and limits is reused."""
    cache = SolvedPeriods()
    period = _corner_stroke()[1]
    cache.solve(period, PARAMS, Limits())
    pressed = dataclasses.replace(period, force_n=period.force_n * 1.1)
    slower = Limits(v_max_mps=0.18)
    heavier = HexarotorParams(base_mass_kg=PARAMS.base_mass_kg * 1.05)
    out = [
        cache.solve(pressed, PARAMS, Limits()),
        cache.solve(period, PARAMS, slower),
        cache.solve(period, heavier, Limits()),
    ]
    assert [s.start for s in out] == [PeriodStart.COLD] * 3
    assert cache.stats().hits == 0 and cache.stats().misses == 4
    assert out[1].t_s[-1] > out[0].t_s[-1] * 0.5  # a real solve, not an empty answer


@pytest.mark.slow
def test_cache_keeps_within_its_bytes_dropping_the_least_recently_used() -> None:
    periods = _corner_stroke()
    probe = SolvedPeriods()
    sizes = []
    for p in periods:
        probe.solve(p, PARAMS, Limits())
        sizes.append(probe.stats().nbytes - sum(sizes))
    cache = SolvedPeriods(max_bytes=sizes[0] + sizes[1])  # not room for all three
    cache.solve(periods[0], PARAMS, Limits())
    cache.solve(periods[2], PARAMS, Limits())
    cache.solve(periods[0], PARAMS, Limits())  # used again: periods[2] is now the oldest
    cache.solve(periods[1], PARAMS, Limits())
    stats = cache.stats()
    assert stats.nbytes == sizes[0] + sizes[1] and stats.periods == 2
    assert cache.solve(periods[0], PARAMS, Limits()).start is PeriodStart.REUSED
    assert cache.solve(periods[2], PARAMS, Limits()).start is PeriodStart.COLD


@pytest.mark.slow
def test_a_plan_made_again_is_the_same_plan_and_reports_its_periods_as_reused() -> None:
    period_cache.SOLVED_PERIODS.clear()
    strokes = [StrokeInput(np.array([[0.0, 0.0], [0.1, 0.0]]))]
    cold = plan_writing(strokes, SURFACE, PlanSettings())
    again = plan_writing(strokes, SURFACE, PlanSettings())
    assert np.array_equal(cold.samples.position_m_enu, again.samples.position_m_enu)
    assert cold.force_n is not None and again.force_n is not None
    assert np.array_equal(cold.force_n, again.force_n)
    first, second = cold.feasibility, again.feasibility
    assert [p["start"] for p in first["periods"]] == ["cold"] * 3
    assert [p["start"] for p in second["periods"]] == ["reused"] * 3
    assert [p["ipopt_iterations"] for p in second["periods"]] == [
        p["ipopt_iterations"] for p in first["periods"]
    ]
    assert all(p["ipopt_status"] == "Solve_Succeeded" for p in second["periods"])
    assert (first["periods_reused"], second["periods_reused"]) == (0, 3)
    assert first["ipopt_iterations"] > 0 and second["ipopt_iterations"] == 0
    assert second["ipopt_solve_s"] == 0.0

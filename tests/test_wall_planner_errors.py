"""What the wall planner says when IPOPT finds no trajectory for a period: the limit that rules
it out, by how much, and the stroke; or plainly that no limit is to blame."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from planner.errors import InfeasibleTrajectoryError, PlannerError
from vehicles.hexarotor_sponge import nlp, solver_cache
from vehicles.hexarotor_sponge.diagnosis import least_time_s
from vehicles.hexarotor_sponge.limits import Limits
from vehicles.hexarotor_sponge.nlp import solve_period
from vehicles.hexarotor_sponge.params import HexarotorParams
from vehicles.hexarotor_sponge.plan import PlanSettings, plan_writing
from vehicles.hexarotor_sponge.waypoints import Period, periods_of
from vehicles.kind import StrokeInput
from vehicles.surface import Surface

SURFACE = Surface.of("vertical", (0.0, 3.0, 2.0), 0.0)
PARAMS = HexarotorParams()


def _two_corner_strokes() -> list[Period]:
    stroke = StrokeInput(np.array([[0.0, 0.0], [0.08, 0.0], [0.08, 0.06]]))
    forces = [np.array([2.0, 3.0, 2.5])] * 2
    return periods_of([stroke] * 2, forces, start_m=np.array([0.0, 0.0, 0.06]), standoff_m=0.03)


def test_periods_know_their_stroke_and_keep_their_labels() -> None:
    periods = _two_corner_strokes()
    assert [(p.stroke_index, p.part) for p in periods] == [
        (0, "flight to it"),
        (0, "writing it"),
        (1, "flight to it"),
        (1, "writing it"),
        (1, "leaving it"),
    ]
    assert [p.label for p in periods] == [
        "flight to stroke 0",
        "stroke 0",
        "flight to stroke 1",
        "stroke 1",
        "leave",
    ]


def test_a_time_step_bound_too_short_to_fly_is_named_not_the_speed() -> None:
    """Steps of at most 0.03 s (a fifth of those the steps were counted for) cannot fly the
    0.03 m off the wall within a_max: the message names h_max and the stroke, not v_max, which
    IPOPT's last iterate keeps."""
    settings = PlanSettings(limits=Limits(h_max_s=0.03))
    stroke = StrokeInput(np.array([[0.0, 0.0], [0.05, 0.0]]))
    with pytest.raises(InfeasibleTrajectoryError) as info:
        plan_writing([stroke], SURFACE, settings)
    err = info.value
    assert str(err) == (
        "stroke 0: flight to it: IPOPT found no trajectory (Infeasible_Problem_Detected): "
        "flying 0.030 m from rest within a_max 0.2 m/s^2 takes 0.548 s: its 6 steps need "
        "0.0913 s each, over h_max 0.03 s by a factor 3"
    )
    assert (err.limit, err.stroke_index, err.bound) == ("h_max", 0, 0.03)
    assert err.value == pytest.approx(np.sqrt(2.0 * 0.03 / 0.2) / 6)


def test_a_force_ramp_beyond_the_time_step_bound_names_it_and_the_stroke() -> None:
    """Lifting the pen off from 2.5 N takes 1.25 s at 2 N/s; the 11 steps counted for it give
    1.1 s at h_max 0.1 s. Said of the second stroke, with the force rate that sets the time."""
    period = _two_corner_strokes()[3]
    with pytest.raises(InfeasibleTrajectoryError) as info:
        solve_period(period, PARAMS, Limits(h_max_s=0.1, corridor_m=None))
    err = info.value
    assert str(err) == (
        "stroke 1: writing it: IPOPT found no trajectory (Infeasible_Problem_Detected): "
        "lifting off from 2.50 N at (0.080, 0.060) m within force_rate_max 2 N/s takes 1.25 s: "
        "its 11 steps need 0.114 s each, over h_max 0.1 s by 13.6%"
    )
    assert (err.limit, err.stroke_index) == ("h_max", 1)
    assert err.value == pytest.approx(1.25 / 11)


def _failing(status: str, iterate: str) -> Any:
    """``nlp._solve`` that reports ``status``, with its own result (``solved``) or the start it
    was given (``start``) as the last iterate."""
    solve = nlp._solve

    def failing(n: int, rows: bool, problem: Any, params: Any, limits: Any, cap: int) -> Any:
        w, stats, iterations, ipopt_s = solve(n, rows, problem, params, limits, cap)
        w = w if iterate == "solved" else problem.guess
        return w, {**stats, "success": False, "return_status": status}, iterations, ipopt_s

    return failing


def test_a_last_iterate_beyond_a_limit_is_named_as_the_iterate(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """IPOPT stopping early (here: on its start) leaves an iterate beyond a_max though the
    period is feasible: the message says it is the last iterate's, with IPOPT's status."""
    monkeypatch.setattr(nlp, "_solve", _failing("Maximum_Iterations_Exceeded", "start"))
    with pytest.raises(InfeasibleTrajectoryError) as info:
        solve_period(_two_corner_strokes()[1], PARAMS, Limits(corridor_m=None))
    err = info.value
    assert str(err).startswith(
        "stroke 0: writing it: IPOPT found no trajectory (Maximum_Iterations_Exceeded): "
        "its last iterate exceeds a_max by a factor 2.3: 0.456 m/s^2 against 0.2 m/s^2 at "
    )
    assert (err.limit, err.stroke_index, err.bound) == ("a_max", 0, 0.2)


def test_an_ipopt_failure_within_every_limit_blames_none(monkeypatch: pytest.MonkeyPatch) -> None:
    """A failure whose last iterate keeps every limit (here: IPOPT's own solution, reported as
    a restoration failure) says so, and which limits the iterate reaches, naming none."""
    monkeypatch.setattr(nlp, "_solve", _failing("Restoration_Failed", "solved"))
    with pytest.raises(PlannerError) as info:
        solve_period(_two_corner_strokes()[1], PARAMS, Limits())
    err = info.value
    assert not isinstance(err, InfeasibleTrajectoryError)
    assert err.stroke_index == 0
    assert str(err).startswith(
        "stroke 0: writing it: IPOPT found no trajectory (Restoration_Failed), yet no limit is "
        "exceeded by its last iterate or by the time the waypoints need; it reaches "
    )


def test_least_time_within_speed_and_acceleration() -> None:
    # 3 cm from rest to rest at 0.2 m/s^2 never reaches 0.2 m/s: 2 sqrt(d / a).
    short_s, short_by = least_time_s(0.03, 2, 0.2, 0.2)
    assert short_s == pytest.approx(2 * np.sqrt(0.15))
    assert short_by == "within a_max 0.2 m/s^2"
    # 50 cm: 10 cm of ramps at both ends, the rest at 0.2 m/s.
    assert least_time_s(0.5, 2, 0.2, 0.2)[0] == pytest.approx(0.5 / 0.2 + 1.0)
    assert least_time_s(0.5, 1, 0.2, 0.2)[0] == pytest.approx(0.5 / 0.2 + 0.5)
    cruise_s, cruise_by = least_time_s(0.5, 0, 0.2, 0.2)
    assert cruise_s == pytest.approx(2.5)
    assert cruise_by == "within v_max 0.2 m/s"
    # At the ramp's length both expressions agree.
    assert least_time_s(0.1, 1, 0.2, 0.2)[0] == pytest.approx(1.0)


@pytest.mark.parametrize("name", ["v_max_mps", "a_max_mps2", "force_rate_max_nps", "h_max_s"])
@pytest.mark.parametrize("value", [0.0, -1.0, math.nan])
def test_a_limit_that_is_not_positive_is_refused_by_name(name: str, value: float) -> None:
    with pytest.raises(PlannerError, match=f"planner limit {name} must be positive") as err:
        Limits(**{name: value})
    assert err.value.field == name


def test_an_attempt_with_a_retry_after_it_stops_early(monkeypatch: pytest.MonkeyPatch) -> None:
    """In corridors a period IPOPT finds no trajectory for is tried again with more steps; the
    attempts before the last stop at the trial cap (a doomed first attempt burned 600 iterations,
    2.2 s of CPU, before the retry planned it in 19), the last has the full cap, and each
    attempt has more steps than the one before."""
    failing = _failing("Maximum_Iterations_Exceeded", "start")
    calls: list[tuple[int, bool, int]] = []

    def recorded(n: int, rows: bool, problem: Any, params: Any, limits: Any, cap: int) -> Any:
        calls.append((n, rows, cap))
        return failing(n, rows, problem, params, limits, cap)

    monkeypatch.setattr(nlp, "_solve", recorded)
    with pytest.raises(PlannerError):
        solve_period(_two_corner_strokes()[1], PARAMS, Limits())
    screening = [(n, cap) for n, rows, cap in calls if not rows]
    caps = [cap for _, cap in screening]
    assert caps == [solver_cache.TRIAL_MAX_ITERATIONS] * 2 + [solver_cache.MAX_ITERATIONS]
    assert solver_cache.TRIAL_MAX_ITERATIONS < solver_cache.MAX_ITERATIONS
    steps = [n for n, _ in screening]
    assert steps == sorted(steps) and len(set(steps)) == 3

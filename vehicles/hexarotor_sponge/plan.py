"""The hexarotor's job plan: strokes on the wall -> optimised periods -> one stitched reference.

``plan_writing`` is the paper's planner (eq. 7 per period, stitched, resampled at the control
rate, section IV), with our extensions: the pen held on the strokes between waypoints
(``corridor``), strokes planned in pieces (``long_periods``). ``plan_equal_distance`` is the
paper's planning baseline (section VII-C): the waypoints sampled at equal distance at constant
speed, positions and forces only (no velocity, acceleration or contact-wrench feed-forward).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from planner.errors import InfeasibleTrajectoryError, PlannerError
from planner.samples import TrajectorySamples
from vehicles.hexarotor_sponge import defaults
from vehicles.hexarotor_sponge.allocation import Allocator
from vehicles.hexarotor_sponge.limits import Limits
from vehicles.hexarotor_sponge.long_periods import split_long
from vehicles.hexarotor_sponge.nlp import PeriodSolution, PeriodStart
from vehicles.hexarotor_sponge.params import GRAVITY_MPS2, HexarotorParams
from vehicles.hexarotor_sponge.period_cache import solve_period_reusing
from vehicles.hexarotor_sponge.waypoints import Period, periods_of, stroke_forces_n
from vehicles.kind import StrokeInput, WritingPlan
from vehicles.surface import Surface

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class PlanSettings:
    """What the planner needs besides the strokes."""

    params: HexarotorParams = field(default_factory=HexarotorParams)
    """The vehicle."""
    limits: Limits = field(default_factory=Limits)
    """Speed, acceleration and force-rate limits, solver weights."""
    default_width_m: float = defaults.DEFAULT_WIDTH_M
    """Line width in [m] of strokes that carry none."""
    clamp_widths: bool = defaults.CLAMP_WIDTHS
    """Clamp widths outside the pen's range (counted in the feasibility report) instead of
    refusing them."""
    standoff_m: float = 0.03
    """Distance in [m] from the wall of the free-flight waypoints."""
    control_dt_s: float = 0.01
    """Sample period of the reference in [s]."""
    reach_m: float = defaults.REACH_M
    """Largest distance in [m] of a stroke point from the writing area's centre (1 mm more is
    let through: ``defaults.REACH_SLACK_M``)."""
    longest_period_steps: int = 117
    """Most steps one contact period may need (``steps.steps_per_segment``, before they are
    rounded up the ladder of built solvers): a longer stroke is planned in pieces from rest to
    rest (``long_periods``)."""


def _checked_strokes(
    strokes: Sequence[StrokeInput], settings: PlanSettings
) -> tuple[list[StrokeInput], list[FloatArray], int]:
    """Strokes with widths clamped if asked, their forces, and how many widths were clamped."""
    pen = settings.params.pen
    out, forces, clamped = [], [], 0
    if not strokes:
        raise PlannerError("nothing to write", field="strokes")
    for k, stroke in enumerate(strokes):
        distance = np.linalg.norm(stroke.xy_m, axis=1)
        far = np.flatnonzero(distance > settings.reach_m + defaults.REACH_SLACK_M)
        if far.size:
            raise PlannerError(
                f"point is {float(distance[far[0]]):.3f} m from the wall's writing centre, "
                f"beyond the reach {settings.reach_m:g} m",
                stroke_index=k,
                point_index=int(far[0]),
            )
        if stroke.width_m is not None and settings.clamp_widths:
            widths, changed = pen.clamp_width_m(stroke.width_m)
            clamped += changed
            stroke = StrokeInput(stroke.xy_m, widths)
        try:
            forces.append(stroke_forces_n(stroke, pen, settings.default_width_m))
        except PlannerError as err:
            raise PlannerError(
                err.message, stroke_index=k, point_index=err.point_index, field="w"
            ) from None
        _check_static_thrust(float(forces[-1].max()), k, settings.params)
        out.append(stroke)
    return out, forces, clamped


def _check_static_thrust(force_n: float, stroke_index: int, params: HexarotorParams) -> None:
    """Refuse a stroke whose hover-and-press wrench (weight, the stroke's largest force with
    sliding friction, their moments) already needs a rotor beyond its limits."""
    alloc = Allocator(params)
    friction = params.wall_friction * force_n
    force_body = np.array([force_n, 0.0, params.mass_kg * GRAVITY_MPS2 + friction])
    weight_body = np.array([0.0, 0.0, -params.mass_kg * GRAVITY_MPS2])
    contact_body = np.array([-force_n, 0.0, -friction])
    torque = -np.cross(params.com_m_body, weight_body) - np.cross(params.tip_m_body, contact_body)
    thrusts = alloc.inverse @ np.concatenate([force_body, torque])  # the exact allocation
    need, least = float(np.max(thrusts)), float(np.min(thrusts))
    if need > params.thrust_max_n or least < 0.0:
        if need > params.thrust_max_n:
            why, value, bound = f"a rotor thrust of {need:.2f} N", need, params.thrust_max_n
        else:  # a rotor would have to pull
            why, value, bound = f"a rotor to pull {-least:.2f} N (rotors only push)", least, 0.0
        raise InfeasibleTrajectoryError(
            f"pressing {force_n:.2f} N while hovering needs {why}, beyond the rotors' "
            f"0..{params.thrust_max_n:.2f} N",
            limit="thrust",
            axis=None,
            t_s=0.0,
            value=value,
            bound=bound,
            stroke_index=stroke_index,
        )


def _periods(
    strokes: Sequence[StrokeInput], settings: PlanSettings
) -> tuple[list[StrokeInput], list[Period], int]:
    """The checked strokes, their free-flight and contact periods (from rest at twice the
    standoff in front of the first point) and the count of clamped widths."""
    checked, forces, clamped = _checked_strokes(strokes, settings)
    first = checked[0].xy_m[0]
    start = np.array([first[0], first[1], 2.0 * settings.standoff_m])
    periods = periods_of(checked, forces, start_m=start, standoff_m=settings.standoff_m)
    return checked, periods, clamped


PeriodSolver = Callable[[Period, HexarotorParams, Limits], PeriodSolution]
"""Eq. 7 for one period: :func:`solve_period_reusing` (an identical period's trajectory if one
was solved in this process, else :func:`nlp.solve_period`), or a peer a benchmark compares it
with."""


def plan_writing(
    strokes: Sequence[StrokeInput],
    surface: Surface,
    settings: PlanSettings,
    solve: PeriodSolver = solve_period_reusing,
) -> WritingPlan:
    """The contact-aware motion-force plan of ``strokes`` on a vertical ``surface``."""
    checked, periods, clamped = _periods(strokes, settings)
    periods = split_long(periods, settings.limits, settings.longest_period_steps)
    solutions = []
    for period in periods:
        solutions.append(solve(period, settings.params, settings.limits))
    t, p, v, a, f = _stitch(solutions)
    report = _report(periods, solutions, v, a, f, t, settings, clamped)
    return _as_plan(t, p, v, a, f, checked, surface, settings, report)


def plan_equal_distance(
    strokes: Sequence[StrokeInput], surface: Surface, settings: PlanSettings
) -> WritingPlan:
    """Planning baseline: waypoints at equal distance, constant speed ``v_max``, q and F only."""
    checked, periods, clamped = _periods(strokes, settings)
    pts = np.vstack([pp.points_m for pp in periods])
    fs = np.concatenate([pp.force_n for pp in periods])
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
    step = settings.limits.v_max_mps * settings.control_dt_s
    s = np.arange(0.0, arc[-1] + step, step)
    keep = np.r_[True, np.diff(arc) > 0.0]
    p = np.column_stack([np.interp(s, arc[keep], pts[keep, j]) for j in range(3)])
    f = np.interp(s, arc[keep], fs[keep])
    t = np.arange(s.size, dtype=np.float64) * settings.control_dt_s
    zeros = np.zeros_like(p)
    report = {"planner": "equal-distance baseline", "widths_clamped": clamped}
    return _as_plan(t, p, zeros, zeros, f, checked, surface, settings, report)


def _stitch(
    solutions: Sequence[PeriodSolution],
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """Concatenate the periods' nodes on one clock (each period starts where the last ended)."""
    t, p, v, a, f = [], [], [], [], []
    offset = 0.0
    for i, sol in enumerate(solutions):
        cut = 0 if i == 0 else 1
        t.append(sol.t_s[cut:] + offset)
        p.append(sol.p_m[cut:])
        v.append(sol.v_mps[cut:])
        a.append(sol.a_mps2[cut:])
        f.append(sol.force_n[cut:])
        offset += float(sol.t_s[-1])
    return (
        np.concatenate(t),
        np.vstack(p),
        np.vstack(v),
        np.vstack(a),
        np.concatenate(f),
    )


def _report(
    periods: Sequence[Period],
    solutions: Sequence[PeriodSolution],
    v: FloatArray,
    a: FloatArray,
    f: FloatArray,
    t: FloatArray,
    settings: PlanSettings,
    clamped: int,
) -> dict[str, object]:
    """The plan's feasibility report: per period how it was found (``start``: ``cold`` solved
    now, ``reused`` from an identical period solved before, with that solve's IPOPT status,
    iterations and times), the IPOPT work of this plan (the periods solved now), and the peaks
    against the limits."""
    lim = settings.limits
    rate = np.abs(np.diff(f)) / np.maximum(np.diff(t), 1e-9)
    solved = [s for s in solutions if s.start is PeriodStart.COLD]
    return {
        "planner": "contact-aware motion-force (CasADi/IPOPT)",
        "periods": [
            {
                "label": per.label,
                "contact": per.contact,
                "start": sol.start.value,
                "ipopt_status": sol.status,
                "ipopt_iterations": sol.iterations,
                "ipopt_s": round(sol.ipopt_s, 4),
                "build_and_solve_s": round(sol.solve_s, 4),
                "steps": int(sol.t_s.size - 1),
                "duration_s": round(float(sol.t_s[-1]), 3),
            }
            for per, sol in zip(periods, solutions, strict=True)
        ],
        "periods_reused": len(solutions) - len(solved),
        "ipopt_solve_s": round(sum(s.ipopt_s for s in solved), 4),
        "build_and_solve_s": round(sum(s.solve_s for s in solved), 4),
        "ipopt_iterations": sum(s.iterations for s in solved),
        "peak_speed_mps": round(float(np.linalg.norm(v, axis=1).max()), 4),
        "v_max_mps": lim.v_max_mps,
        "peak_acceleration_mps2": round(float(np.linalg.norm(a, axis=1).max()), 4),
        "a_max_mps2": lim.a_max_mps2,
        "peak_force_rate_nps": round(float(rate.max()), 4),
        "force_rate_max_nps": lim.force_rate_max_nps,
        "widths_clamped": clamped,
    }


def _as_plan(
    t: FloatArray,
    p: FloatArray,
    v: FloatArray,
    a: FloatArray,
    f: FloatArray,
    strokes: Sequence[StrokeInput],
    surface: Surface,
    settings: PlanSettings,
    report: dict[str, object],
) -> WritingPlan:
    """Resample the nodes at the control rate by linear interpolation (the paper's; a cubic
    Hermite curve of the nodes' positions and velocities was measured instead: on the 1 m "8"
    plan IoU 0.945 against 0.953, flown in calm air 0.857 against 0.859) and turn wall
    coordinates into world ENU."""
    grid = np.arange(0.0, t[-1] + 1e-9, settings.control_dt_s)
    if grid[-1] < t[-1] - 1e-9:
        grid = np.append(grid, t[-1])

    def at(values: FloatArray) -> FloatArray:
        return np.column_stack([np.interp(grid, t, values[:, j]) for j in range(3)])

    basis = np.column_stack([surface.x_axis_enu, surface.y_axis_enu, surface.normal_enu])
    pos = surface.to_world(at(p)[:, :2], at(p)[:, 2])
    force = np.interp(grid, t, f)
    samples = TrajectorySamples(
        t_s=grid,
        position_m_enu=pos,
        velocity_mps_enu=at(v) @ basis.T,
        acceleration_mps2_enu=at(a) @ basis.T,
        pen_down=force > 1e-3,
    )
    width = settings.params.pen.width_m(force)
    return WritingPlan(
        samples, tuple(strokes), surface, force_n=force, width_m=width, feasibility=report
    )

"""Independent time-optimal references to measure planned durations against (benchmarks, tests).

- :func:`line_min_time_s`: the known answer for a straight rest-to-rest move of length ``L``
  under ``|a| <= a`` and ``|v| <= v``: bang-coast-bang, ``L/v + v/a`` when the cruise speed is
  reached (``L >= v^2/a``), else ``2 sqrt(L/a)``.
- :func:`toppra_duration_s`: the minimum time along the *same geometric path* as a planned
  spline, under the same per-axis acceleration bounds and speed limit, by TOPP-RA (PyPI
  ``toppra``, a dev dependency imported lazily: the planner itself never needs it).

The speed limit is a bound on ``||dp/dt||``, not per axis. TOPP-RA bounds joint velocities one by
one, so the path gets a fourth coordinate, its arc length ``sigma(s)``: ``d sigma/ds = ||p'(s)||``
and bounding that coordinate's velocity by ``v_max`` bounds the speed exactly (its acceleration
is left free). The path parameter ``s`` is the planned time.

Rest-to-rest ends: where ``p'`` and ``p''`` vanish together TOPP-RA's controllable sets break down
numerically, so the first and last fraction of a millimetre (planned speed below
``END_SPEED_SHARE * v_max``, a straight piece) are timed apart, at full acceleration from rest
over their length; TOPP-RA times the rest starting and ending at the speed so reached.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from planner.bspline import ClampedCubicSpline, FloatArray

FREE_BOUND = 1e6
"""Bound standing for "no limit" in TOPP-RA's tables (it wants finite numbers)."""
END_SPEED_SHARE = 0.02
"""The ends where the planned speed is below this share of ``v_max`` are timed apart."""


def line_min_time_s(length_m: float, a_max_mps2: float, v_max_mps: float) -> float:
    """Minimum rest-to-rest time [s] along a straight line of ``length_m`` [m]."""
    if length_m <= 0.0:
        return 0.0
    if length_m >= v_max_mps**2 / a_max_mps2:
        return length_m / v_max_mps + v_max_mps / a_max_mps2
    return 2.0 * math.sqrt(length_m / a_max_mps2)


class SplinePath:
    """A planned spline as a TOPP-RA geometric path: x, y, z and arc length, parameter = time.

    ``interval_s`` restricts it to a part of ``[0, duration_s]``.
    """

    def __init__(
        self,
        spline: ClampedCubicSpline,
        interval_s: tuple[float, float] | None = None,
        arc_samples: int = 20_000,
    ) -> None:
        self.spline = spline
        self.interval_s = (0.0, spline.duration_s) if interval_s is None else interval_s
        self._s = np.linspace(0.0, spline.duration_s, arc_samples)
        speed = np.linalg.norm(spline.evaluate(self._s, 1), axis=1)
        steps = 0.5 * (speed[1:] + speed[:-1]) * np.diff(self._s)
        self._arc = np.concatenate([[0.0], np.cumsum(steps)])

    def arc_length_m(self, s: float) -> float:
        """Length of the path from its start to planned time ``s``, [m]."""
        return float(np.interp(s, self._s, self._arc))

    @property
    def dof(self) -> int:
        """Degrees of freedom: x, y, z and the arc length."""
        return 4

    @property
    def path_interval(self) -> FloatArray:
        """First and last path parameter (the planned times), [s]."""
        return np.array(self.interval_s)

    @property
    def waypoints(self) -> None:
        """No waypoints (TOPP-RA asks)."""
        return None

    def __call__(self, path_positions: Any, order: int = 0) -> FloatArray:
        s = np.atleast_1d(np.asarray(path_positions, dtype=np.float64))
        s = np.clip(s, *self.interval_s)
        if order == 0:
            extra = np.interp(s, self._s, self._arc)
            out = np.column_stack([self.spline.evaluate(s, 0), extra])
        else:
            vel = self.spline.evaluate(s, 1)
            speed = np.linalg.norm(vel, axis=1)
            if order == 1:
                extra = speed
            else:
                acc = self.spline.evaluate(s, 2)
                dot = np.sum(vel * acc, axis=1)
                extra = np.divide(dot, speed, out=np.zeros_like(dot), where=speed > 1e-12)
            out = np.column_stack([self.spline.evaluate(s, order), extra])
        return out[0] if np.ndim(path_positions) == 0 else out

    def eval(self, s: Any) -> FloatArray:
        return self(s, 0)

    def evald(self, s: Any) -> FloatArray:
        return self(s, 1)

    def evaldd(self, s: Any) -> FloatArray:
        return self(s, 2)


def toppra_duration_s(
    spline: ClampedCubicSpline,
    accel_lower_mps2: tuple[float, float, float],
    accel_upper_mps2: tuple[float, float, float],
    v_max_mps: float,
    *,
    grid_step_s: float = 0.005,
) -> float:
    """Time-optimal duration [s] of ``spline``'s geometric path, rest to rest, by TOPP-RA.

    Grid points every ``grid_step_s`` of planned time (at least 1000; a coarser grid gives a
    slightly longer, i.e. more lenient, reference: ~1 % at 20 ms, ~0.2 % at 5 ms). Raises
    ``RuntimeError`` when TOPP-RA finds no parameterisation (it then cannot serve as one).
    """
    import toppra  # noqa: F401  (dev dependency)
    import toppra.algorithm as algo
    import toppra.constraint as constraint

    s0, s1 = _moving_interval(spline, v_max_mps)
    path = SplinePath(spline, (s0, s1))
    velocity = spline.evaluate(np.array([s0, s1]), 1)
    speed_at = np.linalg.norm(velocity, axis=1)
    bound = np.minimum(-np.asarray(accel_lower_mps2), np.asarray(accel_upper_mps2))
    a_end = [_accel_along(bound, v / s) for v, s in zip(velocity, speed_at, strict=True)]
    ends = [path.arc_length_m(s0), path.arc_length_m(spline.duration_s) - path.arc_length_m(s1)]
    end_speed = [min(math.sqrt(2.0 * a * d), v_max_mps) for a, d in zip(a_end, ends, strict=True)]
    ends_s = sum(_piece_time_s(d, v, a) for d, v, a in zip(ends, end_speed, a_end, strict=True))
    sd_ends = [v / p for v, p in zip(end_speed, speed_at, strict=True)]
    vlim = np.array([[-FREE_BOUND, FREE_BOUND]] * 3 + [[-v_max_mps, v_max_mps]])
    bounds = zip(accel_lower_mps2, accel_upper_mps2, strict=True)
    alim = np.array([*bounds, (-FREE_BOUND, FREE_BOUND)])
    interp = constraint.DiscretizationType.Interpolation
    constraints = [
        constraint.JointVelocityConstraint(vlim),
        constraint.JointAccelerationConstraint(alim, discretization_scheme=interp),
    ]
    step = grid_step_s
    for attempt in range(4):
        grid = np.linspace(s0, s1, max(1000, math.ceil((s1 - s0) / step)) + 1)
        instance = algo.TOPPRA(constraints, path, gridpoints=grid, solver_wrapper="seidel")
        if attempt == 3:  # last resort: stop at both joints (a little more lenient)
            sd_ends = [0.0, 0.0]
            ends_s = sum(line_min_time_s(d, a, v_max_mps) for d, a in zip(ends, a_end, strict=True))
        _, sd_vec, _ = instance.compute_parameterization(sd_ends[0], sd_ends[1])
        if sd_vec is not None and np.all(np.isfinite(sd_vec)):
            sd = np.asarray(sd_vec, dtype=np.float64)
            inner = float(np.sum(2.0 * np.diff(grid) / np.maximum(sd[1:] + sd[:-1], 1e-12)))
            return inner + ends_s
        step *= 1.5
    raise RuntimeError("TOPP-RA found no parameterisation of the path")


def _accel_along(bound_mps2: FloatArray, direction: FloatArray) -> float:
    """Largest acceleration along the unit ``direction`` within per-axis bounds."""
    share = np.abs(direction)
    return float(np.min(bound_mps2[share > 1e-12] / share[share > 1e-12]))


def _piece_time_s(length_m: float, end_speed_mps: float, a_mps2: float) -> float:
    """Time from rest over ``length_m`` accelerating at ``a_mps2`` up to ``end_speed_mps``."""
    if end_speed_mps <= 0.0:
        return 0.0
    ramp_m = end_speed_mps**2 / (2.0 * a_mps2)
    return end_speed_mps / a_mps2 + max(length_m - ramp_m, 0.0) / end_speed_mps


def _moving_interval(spline: ClampedCubicSpline, v_max_mps: float) -> tuple[float, float]:
    """First and last planned time at which the speed exceeds ``END_SPEED_SHARE * v_max``.

    (See the module docstring: the ends are timed apart.)
    """
    t = np.linspace(0.0, spline.duration_s, 20 * spline.n_spans + 1)
    moving = np.flatnonzero(
        np.linalg.norm(spline.evaluate(t, 1), axis=1) > END_SPEED_SHARE * v_max_mps
    )
    if moving.size == 0:
        raise RuntimeError("the path never moves")
    return float(t[moving[0]]), float(t[moving[-1]])

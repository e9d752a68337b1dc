"""The QP of a minimum-jerk fit under limits (eq. 44-54): its rows, their bounds, its data.

Variables are the control points of the three axes stacked, ``x = [tau_x; tau_y; tau_z]``.

- cost ``x^T (w_g G + H^T W H) x - 2 d^T W H x`` (eq. 44), block diagonal, 3 super-diagonals;
- equalities: the six end control points per axis (eq. 54);
- acceleration: ``lo_a <= alpha^2 L_u tau_a <= hi_a`` per axis (eq. 53). The second derivative is
  piecewise linear with these values at the knots, so this bound is exact;
- speed (optional): the hodograph control points ``alpha K_u tau`` (eq. 47-48) are kept inside a
  polytope of 13 direction pairs (axes, face and body diagonals) inscribed in the ball of radius
  ``v_max``; by the convex hull property ``||p'(t)|| <= v_max`` (sufficient, ~11 % margin). The
  lazy strategy of planner.fit_qp imposes them only at hodograph points outside the ball;
- floor (optional): z control points ``>= z_floor`` so that ``z(t) >= z_floor`` (convex hull).

The constraint matrix never depends on ``alpha``: the bounds are divided by ``alpha^e`` instead, so
re-solves during time re-segmentation keep one sparsity pattern (PIQP ``update``). How the QP is
solved (a working set of rows, dense or sparse, axis by axis): planner.fit_qp.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from planner.bspline import FloatArray, IntArray, acceleration_operator, velocity_operator
from planner.coo import CooMatrix, kron, vstack
from planner.minjerk import FitProblem, fixed_control_points, fixed_indices, normal_equations
from planner.qp_solvers import QpData


def _speed_directions() -> FloatArray:
    """13 unit directions: one of each +/- pair of the 26 neighbours of a cube cell."""
    dirs = []
    for v in itertools.product((-1, 0, 1), repeat=3):
        vec = np.array(v, dtype=np.float64)
        first = vec[np.flatnonzero(vec)[0]] if np.any(vec) else 0.0
        if first > 0:
            dirs.append(vec / np.linalg.norm(vec))
    return np.array(dirs)


SPEED_DIRECTIONS = _speed_directions()
SPEED_POLYTOPE_APOTHEM = 1.0 / 1.1280928107595818
"""Bound on ``|n_k . v|`` that keeps the 13-pair polytope inside the unit ball (circumradius 1)."""


@dataclass(frozen=True)
class QpLimits:
    """Linear limits imposed by the QP, world frame ENU."""

    accel_lower_mps2: tuple[float, float, float]
    """Lowest allowed acceleration per axis in [m/s^2] (negative)."""
    accel_upper_mps2: tuple[float, float, float]
    """Highest allowed acceleration per axis in [m/s^2] (positive)."""
    speed_max_mps: float | None = None
    """Bound on the speed ``||v||`` in [m/s]; ``None`` for no velocity constraint."""
    z_floor_m: float | None = None
    """Lowest allowed z in [m] (via the z control points); ``None`` for none."""


@dataclass(frozen=True, eq=False)
class Structure:
    """What a QP of ``n_spans`` spans has whatever the data and ``alpha``: its rows and the
    pattern of its cost (cached per size)."""

    G: CooMatrix
    """All inequality rows: acceleration (3 axes x (m+1)), then speed (13 x (m+2))."""
    exponent: FloatArray
    """Power of alpha in each row's physical value (2 acceleration, 1 velocity)."""
    kind: IntArray
    """0 for an acceleration row, 1 for a speed row."""
    position: IntArray
    """Knot / hodograph index of each row (its place along the trajectory)."""
    A: CooMatrix
    """Equality rows: the six end control points of each axis (eq. 54)."""
    P_rows: IntArray
    P_cols: IntArray
    """Entries of the upper band of ``P``'s three diagonal blocks, row by row."""
    P_gather: IntArray
    """Flat index into the banded ``ab`` (4, n) of each entry of ``P``."""


STRUCTURES_KEPT = 2
"""Structures cached (the latest sizes): a plan's fit and its re-fits at the same size share
one. Each holds 2.1 KiB per span (430 KiB at 200 spans, 10.7 MiB at 5000) and costs 0.2 ms to
build at 50 spans, 0.3 ms at 200, 1 ms at 1000; an Airshow plan fits once, at a size of its
own (36-225 spans). The 32 kept before held 14.4 MiB of a planning worker's heap after 300
distinct characters (``benchmarks/bench_worker_memory.py --distinct 300``: 62 MiB anonymous,
48 MiB with 2 kept) and hit 121 times in 200 jobs, each hit saving under 1 ms of a job's
50-120 ms CPU: a kept worker holds what it reuses, not every size it once planned."""


@lru_cache(maxsize=STRUCTURES_KEPT)
def structure(n_spans: int, with_speed: bool) -> Structure:
    """The rows (acceleration, then speed if ``with_speed``) and cost pattern of ``n_spans``
    (the latest :data:`STRUCTURES_KEPT` cached)."""
    n = n_spans + 3
    acc = kron(np.eye(3), acceleration_operator(n_spans))
    blocks = [acc]
    exponent = [np.full(acc.shape[0], 2.0)]
    kind = [np.zeros(acc.shape[0], dtype=np.int64)]
    position = [np.tile(np.arange(n_spans + 1), 3)]
    if with_speed:
        vel = kron(SPEED_DIRECTIONS, velocity_operator(n_spans))
        blocks.append(vel)
        exponent.append(np.full(vel.shape[0], 1.0))
        kind.append(np.ones(vel.shape[0], dtype=np.int64))
        position.append(np.tile(np.arange(n - 1), SPEED_DIRECTIONS.shape[0]))
    fixed = fixed_indices(n)
    cols = (np.arange(3)[:, None] * n + fixed[None, :]).ravel()
    A = CooMatrix(np.arange(18), cols, np.ones(18), (18, 3 * n))
    # Upper band of one block, row by row: row i holds columns i .. min(i + 3, n - 1).
    row = np.repeat(np.arange(n), 4)
    col = row + np.tile(np.arange(4), n)
    row, col = row[col < n], col[col < n]
    offsets = (np.arange(3) * n)[:, None]
    return Structure(
        G=vstack(blocks),
        exponent=np.concatenate(exponent),
        kind=np.concatenate(kind),
        position=np.concatenate(position),
        A=A,
        P_rows=(offsets + row).ravel(),
        P_cols=(offsets + col).ravel(),
        P_gather=np.tile((3 - (col - row)) * n + col, 3),
    )


@dataclass(frozen=True, eq=False)
class Bounds:
    """Row bounds (``h_l <= G x <= h_u``, divided by ``alpha^e``) and lower box bounds."""

    h_l: FloatArray
    h_u: FloatArray
    x_l: FloatArray


def qp_bounds(problem: FitProblem, limits: QpLimits, st: Structure) -> Bounds:
    """Row bounds divided by ``alpha^e`` (the rows themselves are alpha-free), box bounds."""
    alpha = problem.alpha
    n = problem.n_ctrl
    rows_per_axis = problem.n_spans + 1
    lo = np.repeat(np.asarray(limits.accel_lower_mps2), rows_per_axis) / alpha**2
    hi = np.repeat(np.asarray(limits.accel_upper_mps2), rows_per_axis) / alpha**2
    if limits.speed_max_mps is not None:
        bound = limits.speed_max_mps * SPEED_POLYTOPE_APOTHEM / alpha
        n_vel = st.G.shape[0] - lo.shape[0]
        lo = np.concatenate([lo, np.full(n_vel, -bound)])
        hi = np.concatenate([hi, np.full(n_vel, bound)])
    x_l = np.full(3 * n, -np.inf)
    if limits.z_floor_m is not None:
        x_l[2 * n :] = limits.z_floor_m
    return Bounds(lo, hi, x_l)


def qp_data(
    problem: FitProblem,
    st: Structure,
    bounds: Bounds,
    ab: FloatArray,
    rhs: FloatArray,
    rows: IntArray | None,
) -> QpData:
    """The QP of ``problem`` from its normal equations (``ab`` banded, ``rhs``), with the rows
    ``rows`` of ``st`` only (None: every row)."""
    n = problem.n_ctrl
    P = CooMatrix(st.P_rows, st.P_cols, 2.0 * ab.ravel()[st.P_gather], (3 * n, 3 * n))
    G, h_l, h_u = st.G, bounds.h_l, bounds.h_u
    if rows is not None:
        G, h_l, h_u = G.take_rows(rows), h_l[rows], h_u[rows]
    return QpData(
        P_upper=P,
        c=-2.0 * rhs.T.ravel(),
        A=st.A,
        b=fixed_control_points(problem).T.ravel(),
        G=G,
        h_l=h_l,
        h_u=h_u,
        x_l=bounds.x_l,
        x_u=np.full(3 * n, np.inf),
    )


def build_qp(problem: FitProblem, limits: QpLimits) -> QpData:
    """The full QP of ``problem`` under ``limits`` (objective ``J - d'Wd``), every row present."""
    st = structure(problem.n_spans, limits.speed_max_mps is not None)
    ab, rhs = normal_equations(problem)
    return qp_data(problem, st, qp_bounds(problem, limits, st), ab, rhs, None)


def violated(g: FloatArray, bounds: Bounds) -> NDArray[np.bool_]:
    """Which rows' values ``g`` (``G x``) break their bounds, beyond a relative 1e-9."""
    scale = 1e-9 * (1.0 + float(np.max(np.abs(bounds.h_u))))
    return np.asarray((g > bounds.h_u + scale) | (g < bounds.h_l - scale))

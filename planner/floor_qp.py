"""The fit under the floor alone: one axis, lower bounds on its control points, by an active set.

Where the closed-form fit (eq. 43) keeps every acceleration row and the speed limit but dips
below the floor (z under the writing height, as a min-jerk fit does where a vertical approach
turns into a stroke lying on the floor), the QP of planner.qp_structure is three independent
problems: x and y keep their closed form, z is ``min 1/2 z^T R z - r^T z`` with the end control
points fixed and ``z_j >= floor`` for the others. With ``R`` positive definite and banded this is
solved exactly by a primal-dual active set on the bounds (block principal pivoting, Judice and
Pires 1994): hold the set ``W`` at the floor, solve the rest with one band solve of ``R``'s
principal submatrix (still banded), then move into ``W`` the points that dip and out of it those
whose multiplier ``(R z - r)_j`` is negative; stop when neither happens (the KKT conditions).
From the closed form's dips it takes 2-3 band solves; ``None`` after ``MAX_ROUNDS`` (the caller
then solves the QP).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from planner.band_solve import solve_symmetric_band
from planner.bspline import FloatArray
from planner.minjerk import banded_matvec

MAX_ROUNDS = 12
"""Active-set rounds before giving up (the caller then solves the QP)."""
TOLERANCE_M = 1e-12
"""A control point counts as below the floor beyond this, [m] (as the lazy QP's floor check)."""
MULTIPLIER_TOLERANCE = 1e-10
"""A multiplier counts as negative beyond this share of the largest right-hand side."""


def principal_band(ab_upper: FloatArray, keep: NDArray[np.int64]) -> FloatArray:
    """Upper band storage of ``A[keep][:, keep]`` for ``A`` in upper band storage (u + 1, n)
    and sorted indices ``keep`` (the submatrix of a band matrix is banded, same width)."""
    u = ab_upper.shape[0] - 1
    sub = np.zeros((u + 1, keep.shape[0]))
    for k in range(min(u, keep.shape[0] - 1) + 1):
        gap = keep[k:] - keep[: keep.shape[0] - k]
        near = gap <= u
        sub[u - k, k:] = np.where(near, ab_upper[u - np.minimum(gap, u), keep[k:]], 0.0)
    return sub


def solve_floor(
    ab_upper: FloatArray,
    rhs: FloatArray,
    start: FloatArray,
    fixed: NDArray[np.int64],
    floor_m: float,
) -> FloatArray | None:
    """``argmin 1/2 z^T R z - rhs^T z`` with ``z[fixed] = start[fixed]`` and every other
    ``z_j >= floor_m``; ``R`` in upper band storage (u + 1, n), ``start`` the unconstrained
    optimum (n,). ``None`` when the active set does not settle within ``MAX_ROUNDS``."""
    n = start.shape[0]
    free = np.ones(n, dtype=bool)
    free[fixed] = False
    held = free & (start < floor_m - TOLERANCE_M)
    z = start.copy()
    for _ in range(MAX_ROUNDS):
        known = np.where(held, floor_m, np.where(free, 0.0, start))
        solve = np.flatnonzero(free & ~held)
        z = known.copy()
        if solve.size:
            right = (rhs - banded_matvec(ab_upper, known))[solve]
            z[solve] = solve_symmetric_band(principal_band(ab_upper, solve), right)
        multiplier = banded_matvec(ab_upper, z) - rhs
        dips = free & ~held & (z < floor_m - TOLERANCE_M)
        pulls = held & (multiplier < -MULTIPLIER_TOLERANCE * float(np.max(np.abs(rhs))))
        if not (np.any(dips) or np.any(pulls)):
            return np.asarray(z)
        held = (held | dips) & ~pulls
    return None

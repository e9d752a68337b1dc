"""The minimum-jerk QP solved axis by axis when none of its rows couples the axes.

Why: the QP of planner.qp_structure stacks the control points of the three axes. Its cost is block
diagonal (one band matrix shared by the axes), and its equalities (the end control points), its
acceleration rows and its floor (a box bound on z) each concern one axis: only the rows of the
speed polytope couple them. Without those rows it is three independent QPs of a third of its size
each. PIQP's dense interface factorises in O(n^3), so the three cost about a ninth of the coupled
solve; and an axis with no rows needs no solver at all, its optimum being the closed form
(eq. 43) whenever that keeps the axis's box, as the lazy strategy argues for the whole QP.

Each axis's interior-point iterations stop at their own tolerance, so the solutions agree with
the coupled solve to the solver's accuracy, not to the last bit: on the planner benchmark's
characters x and y to 1e-15 m, z (held by the floor) to 4e-5 m, where the split solve is the
closer of the two to a solve at 1e-13 (9e-6 m against 4e-5 m).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from planner.bspline import FloatArray, IntArray
from planner.coo import CooMatrix
from planner.qp_solvers import QpData, QpSolution


def row_axes(G: CooMatrix, n_per_axis: int) -> IntArray | None:
    """The axis of each row of ``G`` (variables stacked per axis, ``n_per_axis`` each), or
    ``None`` when a row has entries of two axes."""
    entry_axis = G.cols // n_per_axis
    axis = np.zeros(G.shape[0], dtype=np.int64)
    axis[G.rows] = entry_axis
    return axis if bool(np.all(axis[G.rows] == entry_axis)) else None


def _block(matrix: CooMatrix, rows: IntArray, first_col: int, n_cols: int) -> CooMatrix:
    """Rows ``rows`` of ``matrix`` (renumbered from 0) and its columns ``first_col`` on."""
    taken = matrix.take_rows(rows)
    return CooMatrix(taken.rows, taken.cols - first_col, taken.values, (rows.shape[0], n_cols))


def axis_qp(qp: QpData, axis: int, n_per_axis: int, axes_of_rows: IntArray) -> QpData:
    """The QP of one axis: its variables, its equalities, its rows of ``G``, its box.

    ``qp`` must not couple the axes (``axes_of_rows`` from :func:`row_axes`)."""
    first = axis * n_per_axis
    variables = np.arange(first, first + n_per_axis)
    # the rows with an entry of this axis (a count, not np.unique: that loads numpy.ma, 10 ms)
    counts = np.bincount(qp.A.rows[qp.A.cols // n_per_axis == axis], minlength=qp.A.shape[0])
    equalities = np.flatnonzero(counts)
    rows = np.flatnonzero(axes_of_rows == axis)
    return QpData(
        P_upper=_block(qp.P_upper, variables, first, n_per_axis),
        c=qp.c[variables],
        A=_block(qp.A, equalities, first, n_per_axis),
        b=qp.b[equalities],
        G=_block(qp.G, rows, first, n_per_axis),
        h_l=qp.h_l[rows],
        h_u=qp.h_u[rows],
        x_l=qp.x_l[variables],
        x_u=qp.x_u[variables],
    )


def closed_form_solution(part: QpData, closed_form: FloatArray) -> QpSolution | None:
    """``closed_form`` (the optimum without rows or box, eq. 43) as the solution of ``part``,
    or ``None`` when ``part`` has rows or ``closed_form`` breaks its box."""
    if part.G.shape[0] or np.any(closed_form < part.x_l - 1e-12) or np.any(closed_form > part.x_u):
        return None
    return QpSolution(x=closed_form, z=np.zeros(0), status="solved", iterations=0, solve_ms=0.0)


def joined(parts: Sequence[QpSolution], axes_of_rows: IntArray) -> QpSolution:
    """The solution of the whole QP from those of its axes (in axis order).

    Its status is the first part's that did not solve (``"infeasible"`` first), its iterations
    the most of a part's, its time the sum."""
    z = np.zeros(axes_of_rows.shape[0])
    for axis, part in enumerate(parts):
        z[axes_of_rows == axis] = part.z
    words = [part.status for part in parts if part.status != "solved"]
    status = "infeasible" if "infeasible" in words else (words[0] if words else "solved")
    return QpSolution(
        x=np.concatenate([part.x for part in parts]),
        z=z,
        status=status,
        iterations=max(part.iterations for part in parts),
        solve_ms=sum(part.solve_ms for part in parts),
    )

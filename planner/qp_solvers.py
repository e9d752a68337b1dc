"""One small interface over the QP solvers (PIQP default, Clarabel, OSQP).

Problem form (PIQP's)::

    minimise 1/2 x^T P x + c^T x   s.t.   A x = b,   h_l <= G x <= h_u,   x_l <= x <= x_u

``P`` is given as its upper triangle. The matrices are :class:`~planner.coo.CooMatrix`; the
sparse backends convert them to SciPy's CSC (importing ``scipy.sparse`` on their first solve),
PIQP's dense interface (:class:`PiqpDenseBackend`) to numpy arrays, so a process that solves only
small QPs densely never loads SciPy. Every backend returns the primal solution and the net
multiplier ``z = z_upper - z_lower`` of each row of ``G`` (positive when the upper bound is active)
so that ``P x + c + A^T y + G^T z + z_box = 0``. Solver errors become :class:`QpSolverError`.
A backend object may keep its factorisation pattern between calls (PIQP ``update``). Each
backend imports its solver on its first solve, not when it is made: a plan at a fixed total time
often solves no QP (the closed form meets the limits); a default plan solves at least its time
law's (planner.time_law).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
from numpy.typing import NDArray

from planner.bspline import FloatArray
from planner.coo import CooMatrix
from planner.defaults import SOLVERS
from planner.errors import PlannerError

if TYPE_CHECKING:
    import scipy.sparse as sp


class QpSolverError(PlannerError):
    """The QP solver failed for a reason other than infeasibility (numerics, iteration limit)."""


@dataclass(frozen=True, eq=False)
class QpData:
    """Matrices and bounds of one QP (see module docstring)."""

    P_upper: CooMatrix
    """Upper triangle of the Hessian, (n, n), with a fixed sparsity pattern."""
    c: FloatArray
    """Linear cost, shape (n,)."""
    A: CooMatrix
    """Equality rows, (p, n)."""
    b: FloatArray
    """Equality right-hand side, shape (p,)."""
    G: CooMatrix
    """Inequality rows, (q, n)."""
    h_l: FloatArray
    """Lower bounds of ``G x`` (``-inf`` for none), shape (q,)."""
    h_u: FloatArray
    """Upper bounds of ``G x`` (``+inf`` for none), shape (q,)."""
    x_l: FloatArray
    """Lower bounds of ``x`` (``-inf`` for none), shape (n,)."""
    x_u: FloatArray
    """Upper bounds of ``x`` (``+inf`` for none), shape (n,)."""


@dataclass(frozen=True, eq=False)
class QpSolution:
    """Primal solution, net inequality multipliers and solver bookkeeping."""

    x: FloatArray
    """Primal solution, shape (n,)."""
    z: FloatArray
    """Net multiplier of each row of ``G`` (upper minus lower), shape (q,)."""
    status: str
    """``"solved"``, ``"infeasible"`` or the solver's own word for a failure."""
    iterations: int
    """Interior-point (or ADMM) iterations."""
    solve_ms: float
    """Wall time of setup/update plus solve in [ms]."""


class QpBackend(Protocol):
    """Something that solves :class:`QpData`; may reuse work between calls."""

    name: str

    def solve(self, qp: QpData) -> QpSolution: ...


def _same_pattern(a: CooMatrix, b: CooMatrix) -> bool:
    return a.shape == b.shape and np.array_equal(a.rows, b.rows) and np.array_equal(a.cols, b.cols)


def _csc(matrix: CooMatrix) -> sp.csc_matrix:
    """SciPy's CSC matrix of ``matrix`` (explicit zeros kept: the pattern is the entries)."""
    import scipy.sparse as sp

    return sp.csc_matrix((matrix.values, (matrix.rows, matrix.cols)), shape=matrix.shape)


def _dense(matrix: CooMatrix) -> FloatArray:
    """The dense matrix in column-major order, as PIQP's dense interface takes it."""
    return np.asfortranarray(matrix.toarray())


def _piqp_word(piqp: Any, status: Any) -> str:
    return {
        piqp.PIQP_SOLVED: "solved",
        piqp.PIQP_PRIMAL_INFEASIBLE: "infeasible",
        piqp.PIQP_DUAL_INFEASIBLE: "dual-infeasible",
        piqp.PIQP_MAX_ITER_REACHED: "max-iterations",
        piqp.PIQP_NUMERICS: "numerics",
    }.get(status, str(status))


def _piqp_solution(solver: Any, word: str, start: float) -> QpSolution:
    result = solver.result
    return QpSolution(
        x=np.array(result.x),
        z=np.array(result.z_u) - np.array(result.z_l),
        status=word,
        iterations=int(result.info.iter),
        solve_ms=(time.perf_counter() - start) * 1e3,
    )


class PiqpBackend:
    """PIQP sparse interior point; re-solves with the same pattern use ``update``."""

    name = "piqp"

    def __init__(self) -> None:
        self._solver: Any = None
        self._pattern: tuple[CooMatrix, CooMatrix, CooMatrix] | None = None

    def _needs_setup(self, qp: QpData) -> bool:
        if self._pattern is None:
            return True
        p, a, g = self._pattern
        return not (
            _same_pattern(p, qp.P_upper) and _same_pattern(a, qp.A) and _same_pattern(g, qp.G)
        )

    def solve(self, qp: QpData) -> QpSolution:
        import piqp

        start = time.perf_counter()
        args = (
            _csc(qp.P_upper),
            qp.c,
            _csc(qp.A),
            qp.b,
            _csc(qp.G),
            qp.h_l,
            qp.h_u,
            qp.x_l,
            qp.x_u,
        )
        if self._needs_setup(qp):
            self._solver = piqp.SparseSolver()
            self._solver.settings.verbose = False
            self._solver.setup(*args)
            self._pattern = (qp.P_upper, qp.A, qp.G)
        else:
            self._solver.update(*args)
        word = _piqp_word(piqp, self._solver.solve())
        if word != "solved":
            self._pattern = None  # never update a solver that failed
        return _piqp_solution(self._solver, word, start)


class PiqpDenseBackend:
    """PIQP's dense interface: the same interior-point method on numpy arrays (no SciPy), set up
    for every solve. Its KKT factorisation costs O(n^3) against the sparse one's O(n): on this
    planner's QPs 9 ms against 0.6 ms at n = 282 variables (a character of 18 s), 250 ms
    against 1.4 ms at n = 1026 (the longest characters), 8 to 16 ms against 0.8 ms at n = 342
    (one axis of those, planner.axis_qp); the solutions agree to 1e-14."""

    name = "piqp"

    def solve(self, qp: QpData) -> QpSolution:
        import piqp

        start = time.perf_counter()
        solver = piqp.DenseSolver()
        solver.settings.verbose = False
        solver.setup(
            _dense(qp.P_upper),
            qp.c,
            _dense(qp.A),
            qp.b,
            _dense(qp.G),
            qp.h_l,
            qp.h_u,
            qp.x_l,
            qp.x_u,
        )
        return _piqp_solution(solver, _piqp_word(piqp, solver.solve()), start)


def _finite_rows(
    G: sp.csc_matrix, lo: FloatArray, hi: FloatArray
) -> tuple[sp.csr_matrix, FloatArray, NDArray[np.int64], NDArray[np.int64]]:
    """``[G_up; -G_low]`` rows with finite bounds (for ``Gx <= h`` forms), h, and the row maps."""
    import scipy.sparse as sp

    up = np.flatnonzero(np.isfinite(hi))
    low = np.flatnonzero(np.isfinite(lo))
    Gr = sp.csr_matrix(G)
    stacked = sp.vstack([Gr[up], -Gr[low]], format="csr")
    return stacked, np.concatenate([hi[up], -lo[low]]), up, low


class ClarabelBackend:
    """Clarabel interior point (conic form); rebuilt for every solve."""

    name = "clarabel"

    def solve(self, qp: QpData) -> QpSolution:
        import clarabel
        import scipy.sparse as sp

        start = time.perf_counter()
        n = qp.P_upper.shape[0]
        G_all = sp.vstack([_csc(qp.G), sp.identity(n, format="csc")], format="csc")
        lo = np.concatenate([qp.h_l, qp.x_l])
        hi = np.concatenate([qp.h_u, qp.x_u])
        ineq, h, up, low = _finite_rows(sp.csc_matrix(G_all), lo, hi)
        A = sp.vstack([_csc(qp.A), ineq], format="csc")
        rhs = np.concatenate([qp.b, h])
        cones = [clarabel.ZeroConeT(qp.A.shape[0]), clarabel.NonnegativeConeT(ineq.shape[0])]
        settings = clarabel.DefaultSettings()
        settings.verbose = False
        solver = clarabel.DefaultSolver(_csc(qp.P_upper), qp.c, A, rhs, cones, settings)
        sol = solver.solve()
        elapsed = (time.perf_counter() - start) * 1e3
        status = str(sol.status)
        word = (
            "solved"
            if status == "Solved"
            else ("infeasible" if "Infeasible" in status else status.lower())
        )
        duals = np.array(sol.z)[qp.A.shape[0] :]
        q = qp.G.shape[0]
        z_all = np.zeros(q + n)
        np.add.at(z_all, up, duals[: up.shape[0]])
        np.add.at(z_all, low, -duals[up.shape[0] :])
        return QpSolution(
            x=np.array(sol.x),
            z=z_all[:q],
            status=word,
            iterations=int(sol.iterations),
            solve_ms=elapsed,
        )


class OsqpBackend:
    """OSQP (ADMM, first order) for comparison; tight tolerances, polished; rebuilt each call."""

    name = "osqp"

    def solve(self, qp: QpData) -> QpSolution:
        import osqp
        import scipy.sparse as sp

        start = time.perf_counter()
        n = qp.P_upper.shape[0]
        A = sp.vstack([_csc(qp.A), _csc(qp.G), sp.identity(n, format="csc")], format="csc")
        lo = np.concatenate([qp.b, qp.h_l, qp.x_l])
        hi = np.concatenate([qp.b, qp.h_u, qp.x_u])
        solver = osqp.OSQP()
        solver.setup(
            _csc(qp.P_upper),
            qp.c,
            A,
            lo,
            hi,
            verbose=False,
            eps_abs=1e-7,
            eps_rel=1e-7,
            polishing=True,
            max_iter=20000,
        )
        res = solver.solve(raise_error=False)
        elapsed = (time.perf_counter() - start) * 1e3
        status = str(res.info.status).lower()
        word = (
            "solved"
            if status.startswith("solved")
            else ("infeasible" if "infeasible" in status else status)
        )
        p, q = qp.A.shape[0], qp.G.shape[0]
        y = np.zeros(p + q + n) if res.y is None else np.asarray(res.y)
        return QpSolution(
            x=np.asarray(res.x),
            z=y[p : p + q],
            status=word,
            iterations=int(res.info.iter),
            solve_ms=elapsed,
        )


def make_backend(name: str) -> QpBackend:
    """A fresh backend by name: ``"piqp"`` (default), ``"clarabel"`` or ``"osqp"``."""
    if name == "piqp":
        return PiqpBackend()
    if name == "clarabel":
        return ClarabelBackend()
    if name == "osqp":
        return OsqpBackend()
    raise PlannerError(f"unknown QP solver {name!r}; choose one of {SOLVERS}", field="solver")

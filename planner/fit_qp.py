"""Minimum-jerk regression under acceleration and speed limits: the QP of
planner.qp_structure (eq. 44-54), solved on a working set of its rows (:class:`QpFitter`).

The speed limit is the ``v_max`` ball; the QP's rows for it are a polytope inscribed in the ball
(linear, up to 11 % tighter). The lazy strategy imposes them only around hodograph points that
leave the ball, so a fit whose speed is within ``v_max`` keeps it (the time allocation at the
limits, planner.timescale, brings the speed right up to the ball). When the closed form breaks
nothing but the floor, as the default plans' fits do where an approach meets the board, z alone
is held above it by an exact active set (planner.floor_qp) instead of a QP solve: 0.5-0.6 ms
against 1-4 ms for the QP (the same optimum, to PIQP's tolerance).

Only the speed rows couple the axes. A QP without them (no speed limit, or a working set of the
lazy strategy without speed rows, as in every default plan of the planner benchmark's 172
characters) is solved axis by axis (planner.axis_qp) on the dense interface: three QPs of a
third of the size, or the closed form for an axis without rows. The sparse interface solves the
coupled QP (three sparse solves cost more than one).

Which PIQP interface solves (:class:`QpFitter`): the sparse one, unless the caller gives a dense
budget (``PlanOptions.dense_qp_budget_s``; a one-off ``skyquill plan`` does). The sparse interface
takes SciPy matrices, and importing ``scipy.sparse`` costs about 0.2 s once per process; the dense
one needs only numpy but its solve grows with n^3 + n^2 q (n variables, q rows of ``G``). A
process that plans once therefore solves densely as long as the predicted dense time stays within
its budget, and sparsely from the first QP that would exceed it on: as renting skis until the
rent paid equals the price, it pays at most about twice what the better choice in hindsight
would have cost (a default plan solves 0 to 2 QPs; a fixed total time, 10 to 20).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from planner.axis_qp import axis_qp, closed_form_solution, joined, row_axes
from planner.bspline import FloatArray, IntArray, apply_band, velocity_values
from planner.errors import InfeasibleTrajectoryError, PlannerError
from planner.feasibility import AXES
from planner.floor_qp import solve_floor
from planner.minjerk import (
    FitProblem,
    SplineFit,
    closed_form_from_normal_equations,
    evaluate_fit,
    fit_closed_form,
    fixed_indices,
    normal_equations,
)
from planner.qp_solvers import (
    PiqpDenseBackend,
    QpBackend,
    QpData,
    QpSolution,
    QpSolverError,
    make_backend,
)
from planner.qp_structure import (
    Bounds,
    QpLimits,
    Structure,
    qp_bounds,
    qp_data,
    structure,
    violated,
)

DENSE_SECONDS_PER_UNIT = 9e-10
"""Predicted time of one dense PIQP solve of these QPs per unit of ``n^3 + n^2 q`` (n variables, q
inequality rows: the KKT factorisation and the ``G^T G`` it forms every iteration), [s]. Measured
on one core: 2.3e-10 to 4.1e-10 without rows (9 ms at 282 variables, 250 ms at 1026), 6.5e-10 to
8.3e-10 at 384 variables with 194 to 1043 rows (65 to 173 ms, 14 to 16 iterations); the largest,
rounded up, so that the prediction errs towards the sparse interface. One axis's QP (94 to 348
variables, the floor, up to 10 rows) takes 1.8e-10 to 4.8e-10 (0.6 ms at 94 variables, 8 to 16 ms
at 342; load 5-6): the margin leaves every character of the planner benchmark and 鬱 馕 矗 dense
(鬱's four axis QPs: 147 ms predicted). It is not lowered for them: a fixed total time solves 10
to 20 coupled QPs in a row (speed rows; 33 to 65 ms each dense, 2 ms sparse), and a lower
prediction would only spend more of the budget before turning sparse."""


def dense_qp_seconds(n_variables: int, n_rows: int) -> float:
    """Predicted time [s] of one dense PIQP solve: ``n_variables``, ``n_rows`` rows of ``G``."""
    return DENSE_SECONDS_PER_UNIT * n_variables**2 * (n_variables + n_rows)


class QpFitter:
    """Solves constrained fits, keeping one backend so re-solves can reuse its pattern.

    ``strategy="lazy"`` (default) is exact and much faster than ``"full"``: the unconstrained
    optimum is returned as is when it respects every limit (it is then the QP optimum; speed
    rows count only where a hodograph point leaves the ``v_max`` ball), held above the floor
    by planner.floor_qp when that alone breaks; otherwise QPs are solved with a working set of
    rows around the violated ones, grown until the solution respects all limits. The working
    set persists between calls (stable pattern for PIQP ``update`` during re-segmentation).
    ``"full"`` always passes every row (the speed polytope everywhere).

    ``dense_budget_s`` (PIQP only): QPs are solved on PIQP's dense interface while their predicted
    time (:func:`dense_qp_seconds` each; a QP solved axis by axis counts its axes' solves) fits
    in what is left of it; from the first QP that does not fit on, on the sparse one (see the
    module docstring).
    """

    def __init__(
        self,
        limits: QpLimits,
        solver: str = "piqp",
        strategy: str = "lazy",
        dense_budget_s: float = 0.0,
    ) -> None:
        if strategy not in ("lazy", "full"):
            raise PlannerError(f"unknown strategy {strategy!r}", field="strategy")
        self.limits = limits
        self.solver = solver
        self.strategy = strategy
        self._sparse: QpBackend = make_backend(solver)
        dense = solver == "piqp" and dense_budget_s > 0.0
        self._dense: QpBackend | None = PiqpDenseBackend() if dense else None
        self._dense_left_s = dense_budget_s
        self._working: NDArray[np.bool_] | None = None
        self.solves = 0
        self.solve_ms = 0.0
        self.floor_solves = 0
        """Fits held up by the floor alone, solved by planner.floor_qp (no QP solve)."""

    def _dense_for(self, predicted_s: float) -> QpBackend | None:
        """The dense backend while its budget still holds a solve of ``predicted_s`` (then
        spent on it); once it does not, None for this and every later QP, which go to the
        sparse backend (SciPy is then loaded: the sparse solve is the faster one)."""
        if self._dense is not None and predicted_s <= self._dense_left_s:
            self._dense_left_s -= predicted_s
            return self._dense
        self._dense = None
        return None

    def _solution(
        self, qp: QpData, problem: FitProblem, ab: FloatArray, rhs: FloatArray
    ) -> QpSolution:
        """``qp``'s solution: axis by axis (planner.axis_qp) when no row couples the axes and
        the dense budget holds the axes' solves; otherwise the coupled QP, dense while the
        budget holds it. Dense, a third of the size is about a ninth of the time; sparse, three
        solves took 1.1-1.3x the coupled one's time (median plan of 22 characters in a
        long-running process, 17.9-21.3 ms against 15.9-16.5), so the sparse path stays coupled."""
        n = problem.n_ctrl
        axes = row_axes(qp.G, n) if self._dense is not None else None
        if axes is not None:
            parts = [axis_qp(qp, axis, n, axes) for axis in range(len(AXES))]
            free = None
            if any(part.G.shape[0] == 0 for part in parts):
                free = closed_form_from_normal_equations(problem, ab, rhs)
            known = [
                None if free is None else closed_form_solution(part, free[:, axis])
                for axis, part in enumerate(parts)
            ]
            predicted_s = sum(
                dense_qp_seconds(n, part.G.shape[0])
                for part, sol in zip(parts, known, strict=True)
                if sol is None
            )
            dense = self._dense_for(predicted_s)
            if dense is not None:
                solutions = [
                    dense.solve(part) if sol is None else sol
                    for part, sol in zip(parts, known, strict=True)
                ]
                return joined(solutions, axes)
        return self._on_budget(qp)

    def _on_budget(self, qp: QpData) -> QpSolution:
        """``qp`` whole, on the dense backend while the budget holds it, else the sparse one."""
        dense = self._dense_for(dense_qp_seconds(qp.G.shape[1], qp.G.shape[0]))
        return (dense or self._sparse).solve(qp)

    def solve(self, qp: QpData) -> QpSolution:
        """Another QP of the same plan (planner.time_law's), on the backend the dense budget
        still allows."""
        solution = self._on_budget(qp)
        self.solves += 1
        self.solve_ms += solution.solve_ms
        return solution

    def fit(self, problem: FitProblem) -> SplineFit:
        """Optimal constrained fit; raises :class:`InfeasibleTrajectoryError` if none exists."""
        st = structure(problem.n_spans, self.limits.speed_max_mps is not None)
        bounds = qp_bounds(problem, self.limits, st)
        ab, rhs = normal_equations(problem)
        if self.strategy == "full":
            return self._solve(problem, st, bounds, ab, rhs, None)
        if self._working is None or self._working.shape[0] != st.G.shape[0]:
            self._working = np.zeros(st.G.shape[0], dtype=bool)
        if not np.any(self._working):
            free = closed_form_from_normal_equations(problem, ab, rhs)
            floor_ok = self.limits.z_floor_m is None or bool(
                np.all(free[:, 2] >= self.limits.z_floor_m - 1e-12)
            )
            new = self._breaking(st, bounds, free, problem.alpha)
            if not np.any(new):
                if floor_ok:
                    return evaluate_fit(problem, free)
                held, new = self._held_by_floor(problem, st, bounds, ab, rhs, free)
                if held is not None:
                    return held
            self._grow(st, new)
        for _ in range(20):
            fit = self._solve_working(problem, st, bounds, ab, rhs)
            tau = fit.spline.control_points
            new = self._breaking(st, bounds, tau, problem.alpha) & ~self._working
            if not np.any(new):
                return fit
            self._grow(st, new)
        return self._solve(problem, st, bounds, ab, rhs, None)

    def _held_by_floor(
        self,
        problem: FitProblem,
        st: Structure,
        bounds: Bounds,
        ab: FloatArray,
        rhs: FloatArray,
        free: FloatArray,
    ) -> tuple[SplineFit | None, NDArray[np.bool_]]:
        """The QP's optimum when the closed form ``free`` breaks only the floor: x and y as
        they are, z by the active set of planner.floor_qp; ``None`` when that breaks a row
        (or does not settle), for the QP to solve, with the rows it breaks: the QP's working
        set starts from them (from none, its first solve is this fit again, the floor alone
        imposed)."""
        assert self.limits.z_floor_m is not None
        none = np.zeros(st.G.shape[0], dtype=bool)
        z = solve_floor(
            ab, rhs[:, 2], free[:, 2], fixed_indices(problem.n_ctrl), self.limits.z_floor_m
        )
        if z is None:
            return None, none
        tau = free.copy()
        tau[:, 2] = z
        broken = self._breaking(st, bounds, tau, problem.alpha)
        if np.any(broken):
            return None, broken
        self.floor_solves += 1
        return evaluate_fit(problem, tau, method="floor active set"), none

    def _breaking(
        self, st: Structure, bounds: Bounds, tau: FloatArray, alpha: float
    ) -> NDArray[np.bool_]:
        """Rows to impose for control points ``tau`` (n, 3): the acceleration rows they break,
        and the speed rows of every hodograph point outside the ``v_max`` ball. A hodograph
        point inside the ball needs no row (the speed limit is the ball; the polytope is only
        its linear stand-in inside the QP), so the lazy strategy keeps the fits whose speed
        stays within ``v_max`` as they are."""
        new = violated(st.G @ tau.T.ravel(), bounds)
        if self.limits.speed_max_mps is None:
            return new
        n_spans = tau.shape[0] - 3
        hodograph_u = apply_band(velocity_values(n_spans), tau)
        bound_u = self.limits.speed_max_mps / alpha * (1.0 + 1e-9)
        outside = np.linalg.norm(hodograph_u, axis=1) > bound_u
        speed = st.kind == 1
        new[speed] = outside[st.position[speed]]
        return new

    def _grow(self, st: Structure, new: NDArray[np.bool_]) -> None:
        assert self._working is not None
        for kind in (0, 1):
            hit = st.position[new & (st.kind == kind)]
            if hit.size:  # a look-up table, not np.unique: that loads numpy.ma (10 ms)
                near = (hit[:, None] + np.arange(-2, 3)[None, :]).ravel()
                self._working |= (st.kind == kind) & np.isin(st.position, near, kind="table")

    def _solve_working(
        self,
        problem: FitProblem,
        st: Structure,
        bounds: Bounds,
        ab: FloatArray,
        rhs: FloatArray,
    ) -> SplineFit:
        assert self._working is not None
        return self._solve(problem, st, bounds, ab, rhs, np.flatnonzero(self._working))

    def _solve(
        self,
        problem: FitProblem,
        st: Structure,
        bounds: Bounds,
        ab: FloatArray,
        rhs: FloatArray,
        rows: IntArray | None,
    ) -> SplineFit:
        qp = qp_data(problem, st, bounds, ab, rhs, rows)
        sol = self._solution(qp, problem, ab, rhs)
        self.solves += 1
        self.solve_ms += sol.solve_ms
        if sol.status == "infeasible":
            raise diagnose_infeasible(problem, self.limits)
        if sol.status != "solved":
            raise QpSolverError(f"{self.solver} failed: {sol.status}", field="solver")
        tau = sol.x.reshape(3, problem.n_ctrl).T.copy()
        fit = evaluate_fit(problem, tau, method=self.solver)
        sel = slice(None) if rows is None else rows
        g_x = (st.G @ sol.x)[sel]
        alpha_term = float(np.sum(st.exponent[sel] * sol.z * g_x)) / problem.alpha
        scale = max(1.0, float(np.max(np.abs(sol.z), initial=0.0))) * 1e-7
        return replace(
            fit,
            constraint_alpha_term=alpha_term,
            active_constraints=int(np.count_nonzero(np.abs(sol.z) > scale)),
        )


def diagnose_infeasible(problem: FitProblem, limits: QpLimits) -> InfeasibleTrajectoryError:
    """Explain an infeasible QP by the worst limit the unconstrained optimum breaks."""
    spline = fit_closed_form(problem).spline
    accel = spline.acceleration_at_knots()
    times = spline.knot_times_s()
    lo = np.asarray(limits.accel_lower_mps2)
    hi = np.asarray(limits.accel_upper_mps2)
    excess = np.maximum(accel - hi, lo - accel) / np.maximum(hi - lo, 1e-9)
    k, axis = np.unravel_index(int(np.argmax(excess)), excess.shape)
    if excess[k, axis] > 0.0 or limits.speed_max_mps is None:
        value = float(accel[k, axis])
        bound = float(hi[axis] if value > 0 else lo[axis])
        return InfeasibleTrajectoryError(
            f"acceleration limit: {AXES[axis]} reaches {value:+.3f} m/s^2 at t={times[k]:.2f} s"
            f" (bound {bound:+.3f}); allow more time or raise a_max",
            limit="a_max",
            axis=AXES[axis],
            t_s=float(times[k]),
            value=value,
            bound=bound,
        )
    t = np.linspace(0.0, spline.duration_s, 20 * spline.n_spans + 1)
    speed = np.linalg.norm(spline.evaluate(t, 1), axis=1)
    i = int(np.argmax(speed))
    return InfeasibleTrajectoryError(
        f"speed limit: {speed[i]:.3f} m/s at t={t[i]:.2f} s (bound {limits.speed_max_mps:.3f});"
        " allow more time or raise v_max",
        limit="v_max",
        axis=None,
        t_s=float(t[i]),
        value=float(speed[i]),
        bound=float(limits.speed_max_mps),
    )

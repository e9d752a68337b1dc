"""The period NLP (paper eq. 7) of ``n`` steps, built from one step's functions mapped over the
horizon, with its exact gradient, Jacobian and Hessian assembled from one step's derivatives.

CasADi differentiating the whole horizon's SX graph costs about 6 ms of CPU per step every time
a step count is first used (0.36 s for 48 steps); the derivatives of one step are the same at
every step, so they are derived once, evaluated per step by ``map`` and scattered into the
horizon's sparse gradient, Jacobian and Hessian by constant 0/1 matrices (left to CasADi's MX
reverse mode over the map, the gradient alone cost 8x the SX one). Same values and evaluation
time as the horizon's SX derivatives; building a step count takes about 0.02 s instead of
0.36 s (48 steps).

Variables: ``[x_0, u_0, h_0, ..., x_{n-1}, u_{n-1}, h_{n-1}, x_n]``; parameter: per node
``0..n-1`` the wanted force (``nlp.force_rows``: at the start of its chord and its change along
it), then its corridor (``corridor.corridor_rows``); constraints per
step: the RK4 defect (7), ``|a|^2`` (1), rotor thrusts (6, only with thrust rows), ``|v|^2`` (1)
and the corridor rows (2, only with corridor rows: the node's position across its chord's
parabola and along the chord, our extension of eq. 7).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np
from numpy.typing import NDArray

from vehicles.hexarotor_sponge.contact_model import hover_control_n, rk4_step, rotor_thrusts
from vehicles.hexarotor_sponge.corridor import CORRIDOR_PARAMETERS
from vehicles.hexarotor_sponge.params import HexarotorParams

STATE = 7
"""State of a node: position (3), velocity (3), normal force."""
ACTION = 4
"""Action of a step: control force f_a (3), force rate dF/dt."""
NODE = STATE + ACTION + 1
"""Decision variables of one step in the NLP's vector: x_k, u_k, h_k (the last node only x_N)."""
WINDOW = NODE + 3 + 1 + STATE
"""What one step's functions read: x_k, u_k, h_k, f_a and h of the step before, x_{k+1}."""
FORCE_PARAMETERS = 2
"""The wanted force of a node: at its chord's start, and its change to the chord's end."""
STEP_PARAMETERS = FORCE_PARAMETERS + CORRIDOR_PARAMETERS
"""Parameters of a step's node: wanted force (2), its corridor (``corridor.corridor_rows``)."""


@dataclass(frozen=True)
class Rows:
    """Which optional constraint rows a period NLP has."""

    thrust: bool
    """The six rotor thrusts of each step (screened: see ``nlp.solve_own_frame``)."""
    corridor: bool
    """The node's position across and along its chord (``corridor``), our extension."""


def period_nlp(
    n: int,
    rows: Rows,
    params: HexarotorParams,
    weights: tuple[float, ...],
    weight_dh: float,
) -> tuple[dict[str, Any], dict[str, ca.Function]]:
    """The NLP of ``n`` RK4 steps for ``casadi.nlpsol`` and its ``grad_f``, ``jac_g`` and
    ``hess_lag`` options. ``weights``: the cost weights ``(v, u, du, force, time)``;
    ``weight_dh``: the cost per [s^2] of a time step's change from the step before; parameter:
    ``STEP_PARAMETERS`` columns of ``n`` (wanted force, corridor)."""
    fns = _step_functions(rows, params, weights, weight_dh)
    index, size = _windows(n)
    w = ca.MX.sym("w", size)
    force_ref = ca.MX.sym("p", STEP_PARAMETERS * n)
    outside = ca.vertcat(hover_control_n(params), 0.0)
    windows = ca.reshape(ca.vertcat(w, outside)[index.ravel(order="F").tolist()], WINDOW, n)
    has_before = ca.DM([[0.0] + [1.0] * (n - 1)])
    step_p = ca.vertcat(ca.reshape(force_ref, n, STEP_PARAMETERS).T, has_before)
    cost, g = fns.step.map(n)(windows, step_p)
    cost_values, grad_nz = fns.grad.map(n)(windows, step_p)
    g_values, jac_nz = fns.jac.map(n)(windows, step_p)
    lam_f = ca.MX.sym("lam_f")
    lam_g = ca.MX.sym("lam_g", fns.rows * n)
    hess_nz = fns.hess.map(n)(windows, step_p, lam_f, ca.reshape(lam_g, fns.rows, n))

    def scattered(local: ca.Sparsity, nonzeros: Any, part: str) -> Any:
        sparsity, scatter = _scatter(index, size, local, fns.rows, part)
        return ca.MX(sparsity, ca.mtimes(scatter, ca.vec(nonzeros)))

    derivatives = {
        "grad_f": ca.Function(
            "nlp_grad_f",
            [w, force_ref],
            [ca.sum2(cost_values), scattered(fns.grad_sparsity, grad_nz, "grad")],
            ["x", "p"],
            ["f", "grad_f_x"],
        ),
        "jac_g": ca.Function(
            "nlp_jac_g",
            [w, force_ref],
            [ca.vec(g_values), scattered(fns.jac_sparsity, jac_nz, "jac")],
            ["x", "p"],
            ["g", "jac_g_x"],
        ),
        "hess_lag": ca.Function(
            "nlp_hess_l",
            [w, force_ref, lam_f, lam_g],
            [scattered(fns.hess_sparsity, hess_nz, "hess")],
            ["x", "p", "lam_f", "lam_g"],
            ["triu_hess_gamma_x_x"],
        ),
    }
    return {"x": w, "p": force_ref, "f": ca.sum2(cost), "g": ca.vec(g)}, derivatives


@dataclass(frozen=True)
class _StepFunctions:
    """One step's functions of its window (:data:`WINDOW`) and ``[wanted force (2), corridor (7),
    1 if a step comes before]``, and the sparsity of the derivatives' nonzeros in the window."""

    step: ca.Function
    """-> (cost, constraints)."""
    grad: ca.Function
    """-> (cost, the cost gradient's nonzeros)."""
    grad_sparsity: ca.Sparsity
    jac: ca.Function
    """-> (constraints, the constraint Jacobian's nonzeros)."""
    jac_sparsity: ca.Sparsity
    hess: ca.Function
    """(..., cost multiplier, constraint multipliers) -> the Lagrangian Hessian's nonzeros."""
    hess_sparsity: ca.Sparsity
    rows: int
    """Constraint rows of one step."""


@lru_cache(maxsize=8)
def _step_functions(
    rows: Rows, params: HexarotorParams, weights: tuple[float, ...], weight_dh: float
) -> _StepFunctions:
    """One step's cost, constraints and their exact derivatives (see :class:`_StepFunctions`)."""
    z = ca.SX.sym("z", WINDOW)
    p = ca.SX.sym("p", STEP_PARAMETERS + 1)
    x, u, h = z[0:STATE], z[STATE : STATE + ACTION], z[NODE - 1]
    x_end, rate = rk4_step(x, u, h, params)
    defect = z[WINDOW - STATE :] - x_end
    thrusts = rotor_thrusts(x, u, params) if rows.thrust else ca.SX(0, 1)
    rows_p = p[FORCE_PARAMETERS:STEP_PARAMETERS]
    corridor = corridor_terms(x[0:2], rows_p) if rows.corridor else ca.SX(0, 1)
    g = ca.vertcat(defect, ca.sumsqr(rate[3:6]), thrusts, ca.sumsqr(x[3:6]), corridor)
    force_ref = wanted_force(x[0:2], p[0:FORCE_PARAMETERS], rows_p)
    cost = stage_cost(x, u, z[NODE : NODE + 3], force_ref, params, weights) * h
    cost += p[STEP_PARAMETERS] * weight_dh * (h - z[NODE + 3]) ** 2
    lam_f = ca.SX.sym("lam_f")
    lam_g = ca.SX.sym("lam_g", g.numel())
    grad = ca.gradient(cost, z)
    jac = ca.jacobian(g, z)
    hess = ca.hessian(lam_f * cost + ca.dot(lam_g, g), z)[0]
    return _StepFunctions(
        step=ca.Function("step", [z, p], [cost, g]),
        grad=ca.Function("step_grad", [z, p], [cost, grad.nz[:]]),
        grad_sparsity=grad.sparsity(),
        jac=ca.Function("step_jac", [z, p], [g, jac.nz[:]]),
        jac_sparsity=jac.sparsity(),
        hess=ca.Function("step_hess", [z, p, lam_f, lam_g], [hess.nz[:]]),
        hess_sparsity=hess.sparsity(),
        rows=int(g.numel()),
    )


def wanted_force(p_xy: Any, force: Any, corridor: Any) -> Any:
    """The wanted force at a node on the wall at ``p_xy`` (2): its chord start's force plus the
    chord's change times how far along the chord the node is (``u / length``; 0 without a
    corridor, whose rows are zero). Our extension: eq. 7 pins the force at waypoints only, and
    a force interpolated by step index runs ahead of the pen where it speeds up from rest (a
    drawn width ramp was planned 1.5 mm wide of the drawing a quarter along the stroke)."""
    u = ca.dot(corridor[2:4], p_xy) - corridor[4]
    return force[0] + force[1] * u / ca.fmax(corridor[5], 1e-9)


def corridor_terms(p_xy: Any, corridor: Any) -> Any:
    """The node's two corridor rows (``corridor.corridor_rows``) of its position on the wall
    ``p_xy`` (2) and its corridor's parameters (7): across, ``normal . p - k u (length - u)``
    with ``u = direction . p - start``; along, ``direction . p``."""
    along = ca.dot(corridor[2:4], p_xy)
    u = along - corridor[4]
    return ca.vertcat(ca.dot(corridor[0:2], p_xy) - corridor[6] * u * (corridor[5] - u), along)


def stage_cost(
    x: Any,
    u: Any,
    u_prev: Any,
    force_ref: Any,
    params: HexarotorParams,
    weights: tuple[float, ...],
) -> Any:
    """Cost per second of one step (eq. 7a with the force and control terms): speed, control
    force from hover and from the step before, force from the wanted force, and time."""
    weight_v, weight_u, weight_du, weight_force, time_weight = weights
    return (
        weight_v * ca.sumsqr(x[3:6])
        + weight_u * ca.sumsqr(u[0:3] - hover_control_n(params))
        + weight_du * ca.sumsqr(u[0:3] - u_prev)
        + weight_force * (x[6] - force_ref) ** 2
        + time_weight
    )


def _windows(n: int) -> tuple[NDArray[np.int_], int]:
    """(WINDOW, n) indices of each step's window in ``[w; hover f_a (3); 0]``, and the size of
    ``w``: the first step reads the hover control force and no step before it."""
    size = NODE * n + STATE
    start = NODE * np.arange(n)
    index = np.empty((WINDOW, n), dtype=np.int_)
    index[:NODE] = start + np.arange(NODE)[:, None]
    index[NODE : NODE + 3] = start - NODE + STATE + np.arange(3)[:, None]
    index[NODE + 3] = start - 1
    index[NODE + 4 :] = start + NODE + np.arange(STATE)[:, None]
    index[NODE : NODE + 3, 0] = size + np.arange(3)
    index[NODE + 3, 0] = size + 3
    return index, size


def _scatter(
    index: NDArray[np.int_], size: int, local: ca.Sparsity, rows: int, part: str
) -> tuple[ca.Sparsity, ca.DM]:
    """The horizon's sparsity and the 0/1 matrix taking the steps' stacked nonzeros (of the
    ``local`` pattern in a window) to its nonzeros. ``part``: ``grad`` (a column, the sum of
    the steps' gradients), ``jac`` (each step its own ``rows`` constraint rows) or ``hess``
    (the upper triangle of the sum of the steps' blocks). Entries of the window outside ``w``
    (the first step's hover force) are left out."""
    n = index.shape[1]
    local_row, local_col = (np.asarray(a) for a in local.get_triplet())
    source = np.arange(n)[:, None] * local_row.size + np.arange(local_row.size)
    if part == "grad":
        row, col, shape = index[local_row].T, np.zeros_like(source), (size, 1)
        keep = row < size
    elif part == "jac":
        row, col = rows * np.arange(n)[:, None] + local_row, index[local_col].T
        keep, shape = col < size, (rows * n, size)
    else:
        row, col, shape = index[local_row].T, index[local_col].T, (size, size)
        keep = (row < size) & (col < size) & (row <= col)
    sparsity, to_nz = ca.Sparsity.triplet(*shape, row[keep].tolist(), col[keep].tolist(), True)
    scatter = ca.DM.triplet(
        list(to_nz), source[keep].tolist(), [1.0] * int(keep.sum()), sparsity.nnz(), source.size
    )
    return sparsity, scatter

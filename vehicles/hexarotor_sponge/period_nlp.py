"""The period NLP (paper eq. 7) of ``n`` steps, built from one step's functions mapped over the
horizon, with its exact gradient, Jacobian and Hessian assembled from one step's derivatives.

CasADi differentiating the whole horizon's SX graph costs about 6 ms of CPU per step every time
a step count is first used (0.36 s for 48 steps); the derivatives of one step are the same at
every step, so they are derived once, evaluated per step by ``map`` and scattered into the
horizon's sparse gradient, Jacobian and Hessian by constant 0/1 matrices (left to CasADi's MX
reverse mode over the map, the gradient alone cost 8x the SX one). Same values and evaluation
time as the horizon's SX derivatives; building a step count takes about 0.02 s instead of
0.36 s (48 steps).

Variables: ``[x_0, u_0, h_0, ..., x_{n-1}, u_{n-1}, h_{n-1}, x_n]``; parameter: the wanted
force at nodes ``0..n-1``; constraints per step: the RK4 defect (7), ``|a|^2`` (1), rotor
thrusts (6, only with thrust rows) and ``|v|^2`` (1).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np
from numpy.typing import NDArray

from vehicles.hexarotor_sponge.contact_model import hover_control_n, rk4_step, rotor_thrusts
from vehicles.hexarotor_sponge.params import HexarotorParams

STATE = 7
"""State of a node: position (3), velocity (3), normal force."""
ACTION = 4
"""Action of a step: control force f_a (3), force rate dF/dt."""
NODE = STATE + ACTION + 1
"""Decision variables of one step in the NLP's vector: x_k, u_k, h_k (the last node only x_N)."""
WINDOW = NODE + 3 + 1 + STATE
"""What one step's functions read: x_k, u_k, h_k, f_a and h of the step before, x_{k+1}."""


def period_nlp(
    n: int,
    thrust_rows: bool,
    params: HexarotorParams,
    weights: tuple[float, ...],
    weight_dh: float,
) -> tuple[dict[str, Any], dict[str, ca.Function]]:
    """The NLP of ``n`` RK4 steps for ``casadi.nlpsol`` and its ``grad_f``, ``jac_g`` and
    ``hess_lag`` options. ``weights``: the cost weights ``(v, u, du, force, time)``;
    ``weight_dh``: the cost per [s^2] of a time step's change from the step before."""
    fns = _step_functions(thrust_rows, params, weights, weight_dh)
    index, size = _windows(n)
    w = ca.MX.sym("w", size)
    force_ref = ca.MX.sym("force_ref", n)
    outside = ca.vertcat(hover_control_n(params), 0.0)
    windows = ca.reshape(ca.vertcat(w, outside)[index.ravel(order="F").tolist()], WINDOW, n)
    has_before = ca.DM([[0.0] + [1.0] * (n - 1)])
    step_p = ca.vertcat(force_ref.T, has_before)
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
    """One step's functions of its window (:data:`WINDOW`) and ``[wanted force, 1 if a step
    comes before]``, and the sparsity of the derivatives' nonzeros in the window."""

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
    thrust_rows: bool, params: HexarotorParams, weights: tuple[float, ...], weight_dh: float
) -> _StepFunctions:
    """One step's cost, constraints and their exact derivatives (see :class:`_StepFunctions`)."""
    z = ca.SX.sym("z", WINDOW)
    p = ca.SX.sym("p", 2)
    x, u, h = z[0:STATE], z[STATE : STATE + ACTION], z[NODE - 1]
    x_end, rate = rk4_step(x, u, h, params)
    defect = z[WINDOW - STATE :] - x_end
    thrusts = rotor_thrusts(x, u, params) if thrust_rows else ca.SX(0, 1)
    g = ca.vertcat(defect, ca.sumsqr(rate[3:6]), thrusts, ca.sumsqr(x[3:6]))
    cost = stage_cost(x, u, z[NODE : NODE + 3], p[0], params, weights) * h
    cost += p[1] * weight_dh * (h - z[NODE + 3]) ** 2
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

"""Why IPOPT found no trajectory for a period: the limit that rules it out, said to the user.

Each limit of the period NLP is measured as a ratio to its bound (above 1: exceeded):

* the time step bound ``h_max``, by the time the waypoints need: between two waypoints the
  period has a fixed count of steps of at most ``h_max``, and moving the distance within
  ``v_max`` and ``a_max`` (from or to rest at the period's ends) or changing the force within
  ``force_rate_max`` takes at least a known time. IPOPT keeps the variable bounds (time steps,
  force rate, waypoints, rest, contact mode) on every iterate, so a period they rule out shows
  here, not on the iterate (which then only misses the dynamics). This proves the period
  infeasible, so it is named first;
* IPOPT's last iterate against the limits it may leave on its way: speed, acceleration and the
  rotor thrusts' range. Only a symptom: a last iterate of too few iterations may exceed them too.

When neither exceeds a limit the error says so, with IPOPT's status and the limits its last
iterate reaches: IPOPT failed for another reason (iterations, restoration), or the limits rule
the period out in a way the least times do not see (a pen that must be back at its waypoint
after pressing has little speed to start the line with).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from planner.errors import InfeasibleTrajectoryError, PlannerError
from vehicles.hexarotor_sponge.contact_model import acceleration_mps2
from vehicles.hexarotor_sponge.limits import Limits
from vehicles.hexarotor_sponge.params import HexarotorParams
from vehicles.hexarotor_sponge.solver_cache import thrust_function
from vehicles.hexarotor_sponge.waypoints import Period

FloatArray = NDArray[np.float64]

EXCEEDED = 1.001
"""Ratio to its bound above which a limit counts as exceeded: room for IPOPT's tolerances, and
for the least times bounding speed and acceleration everywhere where the NLP bounds them at its
nodes and step starts only (on glyphs A, I, 永 and 中 they are at most 0.9997 of the planned)."""
AT_BOUND = 0.999
"""Ratio to its bound from which a limit counts as reached on the last iterate."""


@dataclass(frozen=True)
class Excess:
    """The worst use of one limit on a period."""

    limit: str
    """``h_max``, ``v_max``, ``a_max``, ``force_rate`` or ``thrust``."""
    ratio: float
    """Value over bound (above 1: exceeded)."""
    value: float
    """The worst value (for ``h_max`` by the waypoints' time: the time step needed) in SI units."""
    bound: float
    """The limit in SI units."""
    t_s: float
    """Where it is worst on the last iterate, in [s] from the period's start."""
    text: str
    """What is exceeded and by how much, for the message."""


@dataclass(frozen=True)
class Iterate:
    """IPOPT's last iterate of a period of ``n`` steps."""

    xs: FloatArray
    """(7, n+1) states: position (3), velocity (3), normal force."""
    us: FloatArray
    """(4, n) actions: control force (3), force rate."""
    hs: FloatArray
    """(n,) time steps in [s]."""


@dataclass(frozen=True)
class Use:
    """One limit's values over the steps of the last iterate."""

    limit: str
    """The limit's name in :class:`Excess`."""
    name: str
    """Its name in messages (as in the planner's limits)."""
    values: FloatArray
    """(n,) per step, in ``unit``."""
    bound: float
    """The upper bound, in ``unit``."""
    unit: str


def infeasible_error(
    period: Period,
    nodes: NDArray[np.int_],
    status: str,
    iterate: Iterate,
    params: HexarotorParams,
    limits: Limits,
) -> PlannerError:
    """The error of a period IPOPT found no trajectory for (``status``) from the waypoints at
    ``nodes``: an :class:`InfeasibleTrajectoryError` naming the limit exceeded most, or a
    :class:`PlannerError` saying that none is and which ones the last iterate reaches."""
    t_s = np.concatenate([[0.0], np.cumsum(iterate.hs)])
    thrusts_n = np.asarray(thrust_function(params)(iterate.xs[:, :-1], iterate.us))
    uses = _iterate_uses(period, iterate, thrusts_n.max(axis=0), params, limits)
    worst = _largest(_time_budget(period, nodes, t_s, limits))
    if worst.ratio <= EXCEEDED:
        least = _below_zero_thrust(thrusts_n.min(axis=0), params.thrust_max_n, t_s[:-1])
        worst = _largest([_over(use, t_s[:-1]) for use in uses] + [least])
    head = f"{period.part}: IPOPT found no trajectory ({status})"
    if worst.ratio <= EXCEEDED:
        return PlannerError(
            f"{head}, yet no limit is exceeded by its last iterate or by the time the waypoints "
            f"need; {_reached(uses)}",
            stroke_index=period.stroke_index,
        )
    return InfeasibleTrajectoryError(
        f"{head}: {worst.text}",
        limit=worst.limit,
        axis=None,
        t_s=worst.t_s,
        value=worst.value,
        bound=worst.bound,
        stroke_index=period.stroke_index,
    )


def _largest(excesses: list[Excess]) -> Excess:
    """The excess of the largest ratio."""
    return max(excesses, key=lambda e: e.ratio)


def _by(ratio: float) -> str:
    """How far a value is over its bound, ``ratio`` times it."""
    return f"by {ratio - 1.0:.1%}" if ratio < 2.0 else f"by a factor {ratio:.2g}"


def _time_budget(
    period: Period, nodes: NDArray[np.int_], t_s: FloatArray, limits: Limits
) -> list[Excess]:
    """The time step against ``h_max`` that the waypoints at ``nodes`` need at least: every run
    of segments to move its distance within ``v_max`` and ``a_max`` and, on the wall, every
    segment to change its force within ``force_rate_max``."""
    steps = np.diff(nodes)
    runs = [(i, j) for i in range(steps.size) for j in range(i + 1, steps.size + 1)]
    need = [_motion(period, i, j, limits) for i, j in runs]
    if period.contact:
        runs += [(i, i + 1) for i in range(steps.size)]
        need += [_force_change(period, i, limits) for i in range(steps.size)]
    excesses = []
    for (i, j), (need_s, what) in zip(runs, need, strict=True):
        count = int(steps[i:j].sum())
        excesses.append(_over_h_max(what, need_s, count, float(t_s[nodes[i]]), limits.h_max_s))
    return excesses


def _over_h_max(what: str, need_s: float, steps: int, t_s: float, h_max_s: float) -> Excess:
    """``what`` takes ``need_s`` in [s] in ``steps`` of at most ``h_max_s``."""
    ratio = need_s / (steps * h_max_s)
    return Excess(
        "h_max",
        ratio,
        need_s / steps,
        h_max_s,
        t_s,
        f"{what} takes {need_s:.3g} s: its {steps} steps need {need_s / steps:.3g} s each, "
        f"over h_max {h_max_s:.3g} s {_by(ratio)}",
    )


_RESTS = {
    (True, True): " from rest to rest",
    (True, False): " from rest",
    (False, True): " to rest",
    (False, False): "",
}
"""How a run of segments is at rest at the period's start and end, for a message."""


def _motion(period: Period, i: int, j: int, limits: Limits) -> tuple[float, str]:
    """Least time in [s] along waypoints ``i`` to ``j`` of ``period`` (at rest at the period's
    ends), and what it is."""
    points = period.points_m
    distance_m = float(np.linalg.norm(np.diff(points[i : j + 1], axis=0), axis=1).sum())
    starts, stops = i == 0, j == points.shape[0] - 1
    need_s, bounds = least_time_s(distance_m, starts + stops, limits.v_max_mps, limits.a_max_mps2)
    whole = starts and stops
    where = "" if whole or not period.contact else f" from {_at(points[i])} to {_at(points[j])}"
    verb = "writing" if period.contact else "flying"
    return need_s, f"{verb} {distance_m:.3f} m{_RESTS[starts, stops]}{where} {bounds}"


def least_time_s(
    distance_m: float, rests: int, v_max_mps: float, a_max_mps2: float
) -> tuple[float, str]:
    """Least time in [s] to move ``distance_m`` along a path within ``v_max_mps`` and
    ``a_max_mps2``, at rest at ``rests`` (0, 1 or 2) of its ends, and the limits that set it."""
    speed = f"v_max {v_max_mps:.3g} m/s"
    if rests == 0:
        return distance_m / v_max_mps, f"within {speed}"
    accel = f"a_max {a_max_mps2:.3g} m/s^2"
    ramp_s = v_max_mps / a_max_mps2
    if distance_m <= rests * v_max_mps * ramp_s / 2.0:
        return rests * math.sqrt(2.0 * distance_m / (rests * a_max_mps2)), f"within {accel}"
    return distance_m / v_max_mps + rests * ramp_s / 2.0, f"within {speed} and {accel}"


def _force_change(period: Period, i: int, limits: Limits) -> tuple[float, str]:
    """Least time in [s] of the force's change over segment ``i`` of a contact period, and
    what it is."""
    before, after = (float(f) for f in period.force_n[i : i + 2])
    if i == 0:
        what = f"pressing to {after:.2f} N at {_at(period.points_m[i])}"
    elif i == period.force_n.size - 2:
        what = f"lifting off from {before:.2f} N at {_at(period.points_m[i])}"
    else:
        what = (
            f"changing the force from {before:.2f} to {after:.2f} N from {_at(period.points_m[i])}"
        )
    rate = limits.force_rate_max_nps
    return abs(after - before) / rate, f"{what} within force_rate_max {rate:.3g} N/s"


def _at(point_m: FloatArray) -> str:
    """A waypoint on the wall, for a message."""
    return f"({point_m[0]:.3f}, {point_m[1]:.3f}) m"


def _iterate_uses(
    period: Period,
    iterate: Iterate,
    top_thrust_n: FloatArray,
    params: HexarotorParams,
    limits: Limits,
) -> list[Use]:
    """The last iterate's time steps, speeds, accelerations, largest rotor thrusts
    (``top_thrust_n``) and force rates (on the wall) per step against their upper bounds."""
    xs, us = iterate.xs, iterate.us
    accel = acceleration_mps2(xs[3:6, :-1].T, xs[6, :-1], us[0:3].T, params)
    uses = [
        Use("h_max", "h_max", iterate.hs, limits.h_max_s, "s"),
        Use("v_max", "v_max", np.linalg.norm(xs[3:6, :-1], axis=0), limits.v_max_mps, "m/s"),
        Use("a_max", "a_max", np.linalg.norm(accel, axis=1), limits.a_max_mps2, "m/s^2"),
        Use("thrust", "thrust_max", top_thrust_n, params.thrust_max_n, "N"),
    ]
    if period.contact:
        rate = np.abs(us[3])
        uses.append(Use("force_rate", "force_rate_max", rate, limits.force_rate_max_nps, "N/s"))
    return uses


def _over(use: Use, t_s: FloatArray) -> Excess:
    """The largest of ``use``'s values (at step times ``t_s``) against its bound."""
    k = int(np.argmax(use.values))
    value, ratio = float(use.values[k]), float(use.values[k]) / use.bound
    return Excess(
        use.limit,
        ratio,
        value,
        use.bound,
        float(t_s[k]),
        f"its last iterate exceeds {use.name} {_by(ratio)}: {value:.3g} {use.unit} against "
        f"{use.bound:.3g} {use.unit} at {t_s[k]:.2f} s",
    )


def _below_zero_thrust(least_n: FloatArray, thrust_max_n: float, t_s: FloatArray) -> Excess:
    """The least rotor thrust (at times ``t_s``) against 0 N, in parts of the thrust range."""
    k = int(np.argmin(least_n))
    value = float(least_n[k])
    return Excess(
        "thrust",
        1.0 - value / thrust_max_n,
        value,
        0.0,
        float(t_s[k]),
        f"its last iterate asks a rotor for {value:.3g} N, below 0 N by "
        f"{-value / thrust_max_n:.1%} of its {thrust_max_n:.3g} N range, at {t_s[k]:.2f} s",
    )


def _reached(uses: list[Use]) -> str:
    """Which limits the last iterate reaches, on how many of its steps."""
    counts = [(use.name, int(np.sum(use.values >= AT_BOUND * use.bound))) for use in uses]
    reached = [f"{name} on {count}" for name, count in counts if count]
    steps = uses[0].values.size
    if not reached:
        return "it reaches no limit either"
    return f"it reaches {', '.join(reached)} of its {steps} steps"

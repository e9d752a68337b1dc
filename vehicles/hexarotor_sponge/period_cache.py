"""Periods solved earlier in this process, reused for identical periods (a bounded cache).

The same glyph is planned several times in one process: a fleet host's planning workers plan
it for every vehicle of the kind given it, a kiosk previews it before it is submitted. And
every letter starts with the same flight to its first stroke and ends with the same flight
away from its last, only elsewhere on the wall. A period is solved in its own frame
(``nlp.solve_period``), so its trajectory depends only on the period in that frame, the
vehicle and the limits; those are the key, and a reused trajectory is bit for bit the one a
new solve would give (IPOPT is deterministic for the same inputs).

IPOPT warm starts were measured instead and are not used (six bench glyphs, 46 periods, 618
iterations cold): the previous period's step per path length as the start's step took 904
iterations, with its mean control force 2397; the primal and dual solution of the previous
period of the same step count, 178-268 iterations where cold took 172 (12 periods). Only a
period re-planned with nearby inputs gains (speed limit +5 %: 177 iterations against 626),
and no caller re-plans one; it would make a plan depend on what the process planned before.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from dataclasses import dataclass, replace

from vehicles.hexarotor_sponge.limits import Limits
from vehicles.hexarotor_sponge.nlp import (
    FloatArray,
    PeriodSolution,
    PeriodStart,
    in_own_frame,
    own_frame_origin_m,
    solve_own_frame,
)
from vehicles.hexarotor_sponge.params import HexarotorParams
from vehicles.hexarotor_sponge.waypoints import Period

MAX_BYTES = 8 * 2**20
"""Largest size in [bytes] of the kept trajectories' arrays (a 48-step period: about 5 kB, so
some 1500 periods, a few hundred letters)."""


@dataclass(frozen=True)
class CacheStats:
    """How often the cache was asked and what it holds."""

    hits: int
    misses: int
    periods: int
    nbytes: int
    """Size in [bytes] of the kept trajectories' arrays."""


def _key(local: Period, params: HexarotorParams, limits: Limits) -> tuple[object, ...]:
    """Everything the trajectory of ``local`` (in its own frame) depends on."""
    return (
        local.contact,
        local.points_m.shape,
        local.points_m.tobytes(),
        local.force_n.tobytes(),
        local.sagittas_m().tobytes(),
        params,
        limits,
    )


def _arrays(solution: PeriodSolution) -> tuple[FloatArray, ...]:
    return (solution.t_s, solution.p_m, solution.v_mps, solution.a_mps2, solution.force_n,
            solution.control_n)  # fmt: skip


def _nbytes(solution: PeriodSolution) -> int:
    return sum(a.nbytes for a in _arrays(solution))


class SolvedPeriods:
    """Trajectories of solved periods in their own frames, least recently used dropped first
    beyond ``max_bytes``; safe to share between threads."""

    def __init__(self, max_bytes: int = MAX_BYTES) -> None:
        self._max_bytes = max_bytes
        self._kept: OrderedDict[tuple[object, ...], PeriodSolution] = OrderedDict()
        self._nbytes = 0
        self._hits = self._misses = 0
        self._lock = threading.Lock()

    def solve(self, period: Period, params: HexarotorParams, limits: Limits) -> PeriodSolution:
        """``nlp.solve_period(period, params, limits)``, reusing an identical period's
        trajectory (``start`` then says so)."""
        local = in_own_frame(period)
        key = _key(local, params, limits)
        with self._lock:
            kept = self._kept.get(key)
            if kept is not None:
                self._kept.move_to_end(key)
                self._hits += 1
        if kept is None:
            kept = solve_own_frame(local, period, params, limits)
            self._keep(key, kept)
            return kept.moved(own_frame_origin_m(period))
        return replace(kept.moved(own_frame_origin_m(period)), start=PeriodStart.REUSED)

    def _keep(self, key: tuple[object, ...], solution: PeriodSolution) -> None:
        size = _nbytes(solution)
        with self._lock:
            self._misses += 1
            if key in self._kept or size > self._max_bytes:
                return
            for array in _arrays(solution):  # shared with every plan that reuses it
                array.setflags(write=False)
            self._kept[key] = solution
            self._nbytes += size
            while self._nbytes > self._max_bytes:
                _, dropped = self._kept.popitem(last=False)
                self._nbytes -= _nbytes(dropped)

    def stats(self) -> CacheStats:
        """Hits and misses so far, and the periods and bytes kept."""
        with self._lock:
            return CacheStats(self._hits, self._misses, len(self._kept), self._nbytes)

    def clear(self) -> None:
        """Forget every kept trajectory (the counts too)."""
        with self._lock:
            self._kept.clear()
            self._nbytes = self._hits = self._misses = 0


SOLVED_PERIODS = SolvedPeriods()
"""The process's cache, shared by every plan of the hexarotor."""


def solve_period_reusing(period: Period, params: HexarotorParams, limits: Limits) -> PeriodSolution:
    """:func:`nlp.solve_period` through the process's cache :data:`SOLVED_PERIODS`."""
    return SOLVED_PERIODS.solve(period, params, limits)

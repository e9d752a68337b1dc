"""How many steps of the period NLP each segment between two waypoints gets: in proportion to
its least travel time (the paper's distance over speed, or in corridors the time of its speed
profile, ``corridor.segment_times_s``) and to its force change, the sum rounded up the ladder of
built solvers (``solver_cache``)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from vehicles.hexarotor_sponge.corridor import segment_times_s
from vehicles.hexarotor_sponge.limits import Limits
from vehicles.hexarotor_sponge.solver_cache import spread_steps, step_count
from vehicles.hexarotor_sponge.waypoints import Period

TRAVEL_SLACK = 1.3
"""Steps allotted per least travel time at ``h_init`` (and ``h_max = 4/3 h_init`` on top) by
the paper's eq. 7 (``Limits.corridor_m = None``), whose period has no retry with more steps."""
CORRIDOR_TRAVEL_SLACK = 1.15
"""The same in corridors, where a period IPOPT finds no trajectory for is tried again with more
steps (``nlp.RETRY_STEP_SCALES``). The least times (``corridor.segment_times_s``) come within
-30 %..+6 % of the planned ones, so 1.15 still leaves ``h_max`` room for the slowest
(1.43 / 1.15 * 0.15 s = 0.19 s). Against 1.3 (both on the step-count ladder of 1.25) it takes
IPOPT's work (iterations times steps) on the 1 m letters 8, 永, &, O from 10.5k, 10.7k, 10.9k,
11.1k to 5.7k, 7.6k, 8.4k, 8.7k: fewer steps, and fewer strokes long enough to be split
(``long_periods``). The cost: 15 of the 215 inputs of ``bench_wall_corpus.py`` (eight cursive
runs, three words, three kiosk drawings, 经) have a first attempt that fails, which their
retries plan (a 5000-point drawing: four, 0.8 -> 2.5 s of CPU). 1.0 left some of the dozen
inputs of its ``--quick`` run unplanned even after their retries."""


def steps_per_segment(period: Period, limits: Limits) -> list[int]:
    """Steps between consecutive waypoints, in proportion to travel time and force change.

    The paper's travel time is distance over speed (from and to rest at the period's ends); a
    contact period in corridors (``limits.corridor_m``) takes the time of its speed profile
    under the corners' speeds (``corridor.segment_times_s``)."""
    d = np.linalg.norm(np.diff(period.points_m, axis=0), axis=1)
    df = np.abs(np.diff(period.force_n))
    if period.contact and limits.corridor_m is not None:
        travel_s = segment_times_s(period, limits.corridor_m, limits.v_max_mps, limits.a_max_mps2)
    else:
        travel_s = np.maximum(d / limits.v_max_mps, np.sqrt(d / limits.a_max_mps2))
        ends = [0, -1]
        travel_s[ends] = np.maximum(travel_s[ends], 2.0 * np.sqrt(d[ends] / limits.a_max_mps2))
    slack = TRAVEL_SLACK if limits.corridor_m is None else CORRIDOR_TRAVEL_SLACK
    by_dist = np.ceil(slack * travel_s / limits.h_init_s)
    by_force = np.ceil(df / (limits.force_rate_max_nps * limits.h_init_s)) + 1
    return [int(max(2, a, b)) for a, b in zip(by_dist, by_force, strict=True)]


def waypoint_nodes(needed: list[int]) -> NDArray[np.int_]:
    """The node of each waypoint (``0`` first, the period's step count last) of segments that
    need ``needed`` steps, their sum rounded up the step-count ladder (``solver_cache``)."""
    steps = spread_steps(needed, step_count(sum(needed)))
    return np.concatenate([[0], np.cumsum(steps)]).astype(int)

"""Strokes planned in pieces: a contact period is split at its sharp turns, and a piece of more
steps than a bound at more waypoints, into periods from rest to rest, the pen kept on the wall at
its force in between.

In a corridor (``corridor``) the pen all but stops at a sharp turn anyway; a rest there costs
little time and takes a near-stop at a near-cusp out of the NLP, where IPOPT could spend its 600
iterations (the 1 m cursive run of six loops, whose loops end in turns of 75 to 96 deg: one of
its pieces of 113 steps ran out of iterations, split at its turns it plans in 15 to 20 each).

IPOPT's work grows with the steps of a period and so does the chance that it runs out of
iterations (the paper's planner on a 1 m cursive word: ``Maximum_Iterations_Exceeded`` after
600). Splitting where the path turns most (``corridor.turns_rad``), where it is slowest in a
corridor anyway, costs little time.
Each piece keeps the stroke's waypoints, forces and parabolas, so the letter is the same.
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Sequence

import numpy as np

from vehicles.hexarotor_sponge.corridor import SHORTEST_CHORD_M, turns_rad
from vehicles.hexarotor_sponge.limits import Limits
from vehicles.hexarotor_sponge.steps import steps_per_segment
from vehicles.hexarotor_sponge.waypoints import Period

SHARP_TURN_RAD = np.radians(60.0)
"""A turn of the stroke (``corridor.turns_rad``) from which a contact period is split there."""
SHORTEST_SHARE = 0.5
"""Least share of the longest period a piece cut off the front of a long period gets (so a
period is not cut into slivers at its slowest corners)."""


def split_long(periods: Sequence[Period], limits: Limits, longest_steps: int) -> list[Period]:
    """``periods`` with every contact period split into pieces from rest to rest at its sharp
    turns (in corridors, ``limits.corridor_m``), and then every piece that needs more than
    ``longest_steps`` steps (``steps.steps_per_segment``) at more waypoints."""
    out: list[Period] = []
    for period in periods:
        if not period.contact:
            out.append(period)
            continue
        sharp = [period] if limits.corridor_m is None else _at_sharp_turns(period)
        for piece in sharp:
            out.extend(_pieces(piece, limits, longest_steps))
    return out


def _at_sharp_turns(period: Period) -> list[Period]:
    """``period`` split at every waypoint between two chords with length where it turns by
    :data:`SHARP_TURN_RAD` or more."""
    lengths = np.linalg.norm(np.diff(period.points_m, axis=0), axis=1)
    inner = np.arange(1, period.points_m.shape[0] - 1)
    movable = (lengths[inner - 1] > SHORTEST_CHORD_M) & (lengths[inner] > SHORTEST_CHORD_M)
    cuts = inner[movable & (turns_rad(period) >= SHARP_TURN_RAD)]
    bounds = [0, *cuts.tolist(), period.points_m.shape[0] - 1]
    return [_part(period, a, b) for a, b in itertools.pairwise(bounds)]


def _pieces(period: Period, limits: Limits, longest_steps: int) -> list[Period]:
    """``period`` cut front to back until every piece fits in ``longest_steps`` (or has no
    waypoint left to cut at)."""
    pieces: list[Period] = []
    rest = period
    while sum(steps_per_segment(rest, limits)) > longest_steps:
        cut = _cut_at(rest, limits, longest_steps)
        if cut is None:
            break
        pieces.append(_part(rest, 0, cut))
        rest = _part(rest, cut, rest.points_m.shape[0] - 1)
    return [*pieces, rest]


def _cut_at(period: Period, limits: Limits, longest_steps: int) -> int | None:
    """The waypoint to cut ``period`` at: of those where the piece before it fits in
    ``longest_steps`` (at least :data:`SHORTEST_SHARE` of it), the sharpest turn; None if
    no waypoint between two chords with length is in reach."""
    needed = np.cumsum(steps_per_segment(period, limits))
    lengths = np.linalg.norm(np.diff(period.points_m, axis=0), axis=1)
    inner = np.arange(1, period.points_m.shape[0] - 1)
    movable = (lengths[inner - 1] > SHORTEST_CHORD_M) & (lengths[inner] > SHORTEST_CHORD_M)
    fits = needed[inner - 1] <= longest_steps - 2  # room for stopping at the cut
    candidates = inner[movable & fits]
    if candidates.size == 0:
        return None
    long_enough = candidates[needed[candidates - 1] >= SHORTEST_SHARE * longest_steps]
    if long_enough.size:
        candidates = long_enough
    return int(candidates[np.argmax(turns_rad(period)[candidates - 1])])


def _part(period: Period, first: int, last: int) -> Period:
    """Waypoints ``first..last`` of ``period`` as a period of their own."""
    sagitta = None if period.sagitta_m is None else period.sagitta_m[first:last]
    return dataclasses.replace(
        period,
        points_m=period.points_m[first : last + 1],
        force_n=period.force_n[first : last + 1],
        sagitta_m=sagitta,
    )

"""The stroke between two waypoints as a parabola through them: the centre line of the corridor
the planned pen path is held in (``corridor``, our extension of the paper's eq. 7).

A chord of a curve lies on its inner side, by up to the thinning tolerance; the parabola
through the chord's ends that fits the stroke between them follows the curve to a fraction of
a millimetre. Where it does not (a loop's top, a hook, a tight spiral's centre), the waypoint
of the stroke farthest from it is kept too (:func:`refined`), so every corridor's centre line
lies within :data:`FIT_TOLERANCE_M` of the stroke, and the turns between neighbouring parabolas
are those of the stroke itself (the corner speeds of ``corridor`` then mean what they say).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

FIT_SAMPLES = 33
"""Points along the stroke between two waypoints, equally spaced by arc length, that a chord's
parabola is fitted to (the stroke is the polyline through its points, not its points alone:
fitted to the points, one point near a waypoint bent a straight run by millimetres)."""
FIT_TOLERANCE_M = 1e-3
"""Largest offset in [m] of the stroke from a chord's parabola before a waypoint is added. The
1 m cursive run of loops had turns of 130 deg between neighbouring parabolas without it, and
IPOPT ran out of iterations on it. 1 mm: a finger's jitter on the kiosk's canvas (a pixel of a
1000 px drawing laid out 1 m wide) stays inside it, so a drawn line is not pinned at every
jittered point; 0.5 mm took the six bench glyphs from 608 to 760 IPOPT iterations for the same
plan IoU (0.95 against 0.95)."""


def _fit(xy_m: FloatArray, a: int, b: int) -> tuple[float, float]:
    """Sagitta in [m] of the parabola through points ``a`` and ``b`` of a stroke (n, 2) that
    fits the polyline between them best (least squares of the offsets from the chord along its
    left normal, against ``4 t (1 - t)`` at their share ``t`` of the chord, at
    :data:`FIT_SAMPLES` points equally spaced along it and at its own points), and the largest
    offset in [m] of those from it."""
    chord = xy_m[b] - xy_m[a]
    length = float(np.linalg.norm(chord))
    if b - a < 2 or length < 1e-9:
        return 0.0, 0.0 if b - a < 2 else float("inf")
    piece = xy_m[a : b + 1]
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(piece, axis=0), axis=1))])
    s = np.union1d(np.linspace(0.0, arc[-1], FIT_SAMPLES), arc)
    rel = np.column_stack([np.interp(s, arc, piece[:, j]) for j in range(2)]) - xy_m[a]
    direction = chord / length
    along = rel @ direction / length
    t = np.clip(along, 0.0, 1.0)
    offset = rel @ np.array([-direction[1], direction[0]])
    shape = 4.0 * t * (1.0 - t)
    sagitta = float(offset @ shape / max(float(shape @ shape), 1e-12))
    beyond = (along - t) * length  # the stroke running back past a waypoint
    residual = float(np.hypot(offset - sagitta * shape, beyond).max())
    return sagitta, residual


def refined(xy_m: FloatArray, kept: NDArray[np.intp]) -> tuple[NDArray[np.intp], FloatArray]:
    """Waypoint indices ``kept`` (ends included, increasing) of a stroke (n, 2) with those added
    that bring every chord's parabola within :data:`FIT_TOLERANCE_M` of the stroke (the point
    between two waypoints farthest from their chord's parabola, until none is), and the
    sagittas (len - 1,) in [m] of the chords' parabolas (see :func:`_fit`)."""
    out = [int(kept[0])]
    sagittas: list[float] = []
    pending = [int(k) for k in kept[1:]][::-1]
    while pending:
        a, b = out[-1], pending[-1]
        sagitta, residual = _fit(xy_m, a, b)
        if residual > FIT_TOLERANCE_M and b - a >= 2:
            pending.append(a + 1 + _farthest(xy_m, a, b, sagitta))
            continue
        out.append(pending.pop())
        sagittas.append(sagitta)
    return np.asarray(out, dtype=np.intp), np.asarray(sagittas)


def _farthest(xy_m: FloatArray, a: int, b: int, sagitta: float) -> int:
    """Index (from ``a + 1``) of the stroke point strictly between ``a`` and ``b`` farthest
    from its chord's parabola of ``sagitta``."""
    chord = xy_m[b] - xy_m[a]
    length = float(np.linalg.norm(chord))
    rel = xy_m[a + 1 : b] - xy_m[a]
    if length < 1e-9:  # a closed stroke: the point farthest from where it starts and ends
        return int(np.argmax(np.linalg.norm(rel, axis=1)))
    direction = chord / length
    t = rel @ direction / length
    offset = rel @ np.array([-direction[1], direction[0]])
    clipped = np.clip(t, 0.0, 1.0)
    miss = np.hypot(offset - sagitta * 4.0 * clipped * (1.0 - clipped), (t - clipped) * length)
    return int(np.argmax(miss))

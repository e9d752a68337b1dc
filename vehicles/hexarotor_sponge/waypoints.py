"""From strokes on the wall to the planner's periods of sparse waypoints (paper section VI-B).

Every stroke becomes one contact period: touch the wall at its first point with no force, press
to the first point's force, slide through the stroke's points with their forces, release at its
last point. Between strokes (and before the first, after the last) a free-flight period leaves the
wall along its normal to ``standoff_m``, flies across, and comes back to the wall.
Our extension: each chord between a contact period's waypoints carries the sagitta of the
parabola through its two waypoints that fits the stroke between them, the centre line of the
corridor its nodes are held in (``corridor``); where no parabola fits, a waypoint is added
(``parabolas.refined``).
Waypoints are in wall coordinates ``(x, y, s)``: reader's x and y on the wall and ``s`` the
distance out of the wall (the contact function ``phi``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from planner.errors import PlannerError
from vehicles.hexarotor_sponge.parabolas import refined
from vehicles.hexarotor_sponge.pen import PenCurve
from vehicles.kind import StrokeInput

FloatArray = NDArray[np.float64]


FORCE_TO_M = 0.01
"""Scale of force against position when waypoints are thinned: 0.2 N of width change counts as
much as 2 mm off the line (so a width profile survives thinning)."""


@dataclass(frozen=True)
class Period:
    """One free-flight or contact period between rest states."""

    contact: bool
    """True: ``phi = 0`` throughout (eq. 7e); False: ``phi >= 0`` and no force."""
    points_m: FloatArray
    """(M, 3) waypoints ``(x, y, s)`` in [m], wall coordinates."""
    force_n: FloatArray
    """(M,) normal force in [N] at each waypoint."""
    stroke_index: int
    """The stroke it flies to, writes or leaves (the last stroke for the final flight away)."""
    part: str
    """What it does for that stroke, for error messages after ``stroke k:``: ``flight to it``,
    ``writing it`` or ``leaving it``."""
    sagitta_m: FloatArray | None = None
    """(M-1,) offset in [m] of the stroke's parabola from each chord's middle, along the chord's
    left normal (its direction turned +90 deg); None: straight chords (free flight)."""

    def sagittas_m(self) -> FloatArray:
        """(M-1,) :attr:`sagitta_m`, zeros for straight chords."""
        if self.sagitta_m is None:
            return np.zeros(self.points_m.shape[0] - 1)
        return self.sagitta_m

    @property
    def label(self) -> str:
        """Which part of the job, for the plan's report (``flight to stroke 3``, ``stroke 2``,
        ``leave``)."""
        if self.part == "flight to it":
            return f"flight to stroke {self.stroke_index}"
        return f"stroke {self.stroke_index}" if self.contact else "leave"


def simplify(points: FloatArray, tolerance: float) -> NDArray[np.intp]:
    """Indices of a polyline (n, d) kept by Douglas-Peucker at ``tolerance`` (ends always kept)."""
    keep = np.zeros(points.shape[0], dtype=bool)
    keep[0] = keep[-1] = True
    stack = [(0, points.shape[0] - 1)]
    while stack:
        i, j = stack.pop()
        if j <= i + 1:
            continue
        ab = points[j] - points[i]
        rel = points[i + 1 : j] - points[i]
        length = float(np.linalg.norm(ab))
        if length < 1e-12:
            dist = np.linalg.norm(rel, axis=1)
        else:
            along = rel @ ab / length
            dist = np.linalg.norm(rel - np.outer(along, ab / length), axis=1)
        k = int(np.argmax(dist))
        if dist[k] > tolerance:
            keep[i + 1 + k] = True
            stack += [(i, i + 1 + k), (i + 1 + k, j)]
    return np.flatnonzero(keep)


def stroke_forces_n(stroke: StrokeInput, pen: PenCurve, default_width_m: float) -> FloatArray:
    """Target force in [N] per stroke point from its wanted widths (or the default width)."""
    n = stroke.xy_m.shape[0]
    widths = np.full(n, default_width_m) if stroke.width_m is None else stroke.width_m
    return pen.force_n(np.asarray(widths, dtype=np.float64))


def periods_of(
    strokes: Sequence[StrokeInput],
    forces_n: Sequence[FloatArray],
    *,
    start_m: FloatArray,
    standoff_m: float,
    tolerance_m: float = 2e-3,
) -> list[Period]:
    """The job as alternating free-flight and contact periods, starting at rest at ``start_m``
    (wall coordinates) and ending at rest ``standoff_m`` off the last stroke's end."""
    periods: list[Period] = []
    here = np.asarray(start_m, dtype=np.float64)
    for k, (stroke, force) in enumerate(zip(strokes, forces_n, strict=True)):
        if np.any(force <= 0.0):
            raise PlannerError("a contact stroke needs a positive force", stroke_index=k)
        thinned = simplify(np.column_stack([stroke.xy_m, force * FORCE_TO_M]), tolerance_m)
        idx, sagittas = refined(stroke.xy_m, thinned)
        on_wall = np.column_stack([stroke.xy_m[idx], np.zeros(idx.size)])
        first, last = on_wall[0], on_wall[-1]
        lift = np.array([0.0, 0.0, standoff_m])
        flight = [here] if here[2] > 0.0 else [here, here + lift]
        flight += [first + lift, first]
        periods.append(_period(False, np.array(flight), None, k, "flight to it"))
        pts = np.vstack([first, on_wall, last])
        f = np.concatenate([[0.0], force[idx], [0.0]])
        sagitta = np.concatenate([[0.0], sagittas, [0.0]])
        periods.append(Period(True, pts, f, k, "writing it", sagitta))
        here = last
    away = here + np.array([0.0, 0.0, standoff_m])
    periods.append(_period(False, np.array([here, away]), None, len(strokes) - 1, "leaving it"))
    return periods


def _period(
    contact: bool, points: FloatArray, force: FloatArray | None, stroke_index: int, part: str
) -> Period:
    f = np.zeros(points.shape[0]) if force is None else force
    return Period(contact, np.asarray(points, dtype=np.float64), np.asarray(f), stroke_index, part)

"""Turning points of a handwritten stroke by split-and-merge (Phang et al. 2015, section 4).

1. connect the first point A and the last point B;
2. find the point C farthest from the line A-B;
3. if that distance is within the threshold the points A..B form one segment;
4. otherwise split into A..C and C..B and recurse;
5. merge: drop a turning point when the points between its two neighbours all lie within the
   threshold of the segment joining them (the merge step of Borges and Aldon [2]).

The endpoints of the final segments, in their original chronological order, are the turning
points. The first and last point of the stroke are always kept.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from planner.errors import PlannerError

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


def _distance_to_segment(points: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
    """Distance of each point to segment a-b (to the point a when a == b), in point units."""
    ab = b - a
    length_sq = float(ab @ ab)
    rel = points - a
    if length_sq != 0.0:
        # Perpendicular distance to the infinite line, as in the paper; for points beyond the
        # ends the distance to the nearer end, so that a stroke that doubles back keeps its far
        # point.
        rel = rel - np.clip(rel @ ab / length_sq, 0.0, 1.0)[:, None] * ab
    return np.asarray(np.sqrt(np.einsum("ij,ij->i", rel, rel)))


def split_and_merge(points: FloatArray, threshold: float) -> IntArray:
    """Indices of the turning points of ``points`` (n, d), increasing, first and last included.

    ``threshold`` is the largest allowed distance (same unit as the points) between any input
    point and the polyline through the turning points. Iterative (no recursion limit).
    """
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[0] < 1:
        raise PlannerError(f"expected an (n, d) array of points, got shape {pts.shape}")
    if not threshold > 0.0:
        raise PlannerError(f"threshold must be > 0, got {threshold}", field="split_threshold_m")
    n = pts.shape[0]
    if n <= 2:
        return np.arange(n, dtype=np.int64)
    keep = np.zeros(n, dtype=bool)
    keep[0] = keep[-1] = True
    stack = [(0, n - 1)]
    while stack:
        i, j = stack.pop()
        if j - i < 2:
            continue
        dist = _distance_to_segment(pts[i + 1 : j], pts[i], pts[j])
        k = int(np.argmax(dist))
        if dist[k] > threshold:
            c = i + 1 + k
            keep[c] = True
            stack.append((c, j))
            stack.append((i, c))
    return _merge(pts, np.flatnonzero(keep).astype(np.int64), threshold)


def _merge(pts: FloatArray, kept: IntArray, threshold: float) -> IntArray:
    """Remove turning points whose two neighbouring segments fit one segment within threshold."""
    indices = list(int(i) for i in kept)
    changed = True
    while changed and len(indices) > 2:
        changed = False
        k = 1
        while k < len(indices) - 1:
            i, j = indices[k - 1], indices[k + 1]
            if float(np.max(_distance_to_segment(pts[i + 1 : j], pts[i], pts[j]))) <= threshold:
                del indices[k]
                changed = True
            else:
                k += 1
    return np.array(indices, dtype=np.int64)


def turning_points(points: FloatArray, threshold: float) -> FloatArray:
    """The turning points themselves, shape (k, d), in chronological order."""
    pts = np.asarray(points, dtype=np.float64)
    return pts[split_and_merge(pts, threshold)]

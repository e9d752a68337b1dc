"""Fidelity to the letter: how far a pen path (planned or flown) lies from the target strokes.

Tracking figures (``rmse_ee_m``) compare the flown tip with the plan; these compare a path with
the letter itself, so a plan that leaves the strokes between its waypoints shows here even when
it is flown perfectly.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from vehicles.kind import StrokeInput

FloatArray = NDArray[np.float64]

CHUNK_POINTS = 2048
"""Path points measured against all stroke segments at once (bounds the temporary arrays)."""


def distance_to_strokes_m(points_m: FloatArray, strokes: Sequence[StrokeInput]) -> FloatArray:
    """(K,) distance in [m] of each surface point (K, 2) from the nearest stroke polyline
    (segment by segment, ends included); (0,) for no points."""
    a = np.vstack([s.xy_m[:-1] for s in strokes])
    b = np.vstack([s.xy_m[1:] for s in strokes])
    ab = b - a
    length2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-18)
    out = np.empty(points_m.shape[0])
    for lo in range(0, points_m.shape[0], CHUNK_POINTS):
        p = points_m[lo : lo + CHUNK_POINTS]
        rel = p[:, None, :] - a[None, :, :]
        t = np.clip(np.einsum("kij,ij->ki", rel, ab) / length2, 0.0, 1.0)
        gap = rel - t[:, :, None] * ab[None, :, :]
        out[lo : lo + CHUNK_POINTS] = np.sqrt(np.einsum("kij,kij->ki", gap, gap).min(axis=1))
    return out


def to_strokes_figures(points_m: FloatArray, strokes: Sequence[StrokeInput]) -> dict[str, float]:
    """``rmse_to_strokes_m`` and ``max_to_strokes_m`` of surface points (K, 2) in [m] against
    the strokes (NaN without points)."""
    if points_m.shape[0] == 0:
        return {"rmse_to_strokes_m": float("nan"), "max_to_strokes_m": float("nan")}
    d = distance_to_strokes_m(points_m, strokes)
    return {
        "rmse_to_strokes_m": float(np.sqrt(np.mean(d**2))),
        "max_to_strokes_m": float(d.max()),
    }

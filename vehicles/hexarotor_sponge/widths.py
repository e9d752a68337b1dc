"""Line widths for strokes that carry none: typed text gets a brush-like profile."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from vehicles.hexarotor_sponge.pen import PenCurve

FloatArray = NDArray[np.float64]


def with_profile_knots(xy_m: FloatArray, taper_m: float = 0.04) -> FloatArray:
    """The stroke with points added where its default profile bends (end of each taper and the
    middle), so that a profile sampled at the points keeps its shape between sparse points."""
    seg = np.linalg.norm(np.diff(xy_m, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    length = float(s[-1])
    knots = np.array([taper_m, 0.5 * length, length - taper_m])
    knots = knots[(knots > 0.0) & (knots < length)]
    grid = np.unique(np.concatenate([s, knots]))
    return np.column_stack([np.interp(grid, s, xy_m[:, 0]), np.interp(grid, s, xy_m[:, 1])])


def default_width_profile(xy_m: FloatArray, pen: PenCurve, *, taper_m: float = 0.04) -> FloatArray:
    """(n,) widths in [m] along a stroke: the pen's middle width, swelling to 80 % of the way
    to its widest in the stroke's middle and narrowing over ``taper_m`` at both ends to its
    narrowest (a press and a lift, as a brush would)."""
    seg = np.linalg.norm(np.diff(xy_m, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    length = float(s[-1])
    lo, hi = pen.width_min_m, pen.width_max_m
    mid = lo + 0.5 * (hi - lo)
    swell = mid + 0.3 * (hi - lo) * np.sin(np.pi * s / max(length, 1e-9))
    to_end = np.minimum(s, length - s)
    taper = np.clip(to_end / taper_m, 0.0, 1.0)
    return np.asarray(lo + (swell - lo) * taper)

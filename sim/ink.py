"""Ink on the board: a boolean raster painted by round brush footprints swept between tip samples.

A footprint of diameter ``w`` moved in a straight line from ``a`` to ``b`` covers a capsule; pixels
whose centres fall inside are inked. Capsules are painted vectorised in chunks. The comparison of a
written and a target raster is their intersection over union (Guo et al. 2024, section VII).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sim.errors import SimError

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.int64]

_CHUNK = 256


@dataclass(frozen=True)
class RasterSpec:
    """Geometry of a board raster in world x, y (the board is horizontal)."""

    origin_m: tuple[float, float]
    """World (x, y) in [m] of the centre of pixel [row 0, column 0]."""
    pixel_m: float
    """Pixel edge length in [m]."""
    shape: tuple[int, int]
    """(rows along y, columns along x)."""

    @classmethod
    def covering(
        cls, points_xy_m: FloatArray, *, pixel_m: float = 0.001, margin_m: float = 0.05
    ) -> RasterSpec:
        """The raster that covers ``points_xy_m`` (n, 2) with ``margin_m`` on every side."""
        if not pixel_m > 0.0:
            raise SimError("must be positive", field="pixel_m")
        pts = np.asarray(points_xy_m, dtype=np.float64).reshape(-1, 2)
        if pts.shape[0] == 0:
            raise SimError("no points to cover", field="points_xy_m")
        lo = pts.min(axis=0) - margin_m
        hi = pts.max(axis=0) + margin_m
        cols = math.ceil((hi[0] - lo[0]) / pixel_m) + 1
        rows = math.ceil((hi[1] - lo[1]) / pixel_m) + 1
        return cls((float(lo[0]), float(lo[1])), pixel_m, (rows, cols))

    def extent_m(self) -> tuple[float, float, float, float]:
        """(x_min, x_max, y_min, y_max) of the pixel edges, for plotting."""
        half = 0.5 * self.pixel_m
        x0, y0 = self.origin_m
        return (
            x0 - half,
            x0 + (self.shape[1] - 0.5) * self.pixel_m,
            y0 - half,
            y0 + (self.shape[0] - 0.5) * self.pixel_m,
        )


class InkCanvas:
    """A raster that brush footprints paint (mutable; painting only ever adds ink)."""

    def __init__(self, spec: RasterSpec) -> None:
        self.spec = spec
        self.pixels: BoolArray = np.zeros(spec.shape, dtype=np.bool_)

    def paint_path(self, points_xy_m: FloatArray, width_m: FloatArray, inked: BoolArray) -> None:
        """Paint the sweep between consecutive samples where both ends are ``inked``.

        ``points_xy_m`` (n, 2); ``width_m`` (n,) footprint diameter; each swept segment uses the
        mean width of its ends. A lone inked sample paints a dot.
        """
        pts = np.asarray(points_xy_m, dtype=np.float64)
        width = np.asarray(width_m, dtype=np.float64)
        ink = np.asarray(inked, dtype=np.bool_) & (width > 0.0)
        both = ink[:-1] & ink[1:]
        radius = 0.25 * (width[:-1] + width[1:])
        self.paint_capsules(pts[:-1][both], pts[1:][both], radius[both])
        alone = ink.copy()
        alone[:-1] &= ~both
        alone[1:] &= ~both
        self.paint_capsules(pts[alone], pts[alone], 0.5 * width[alone])

    def paint_capsules(self, start_m: FloatArray, end_m: FloatArray, radius_m: FloatArray) -> None:
        """Paint capsules from ``start_m`` to ``end_m`` (S, 2) of radius ``radius_m`` (S,)."""
        a, b, r = _split_long(
            np.asarray(start_m, dtype=np.float64).reshape(-1, 2),
            np.asarray(end_m, dtype=np.float64).reshape(-1, 2),
            np.asarray(radius_m, dtype=np.float64).reshape(-1),
            self.spec.pixel_m,
        )
        for lo in range(0, a.shape[0], _CHUNK):
            sl = slice(lo, lo + _CHUNK)
            self._paint_chunk(a[sl], b[sl], r[sl])

    def _paint_chunk(self, a: FloatArray, b: FloatArray, r: FloatArray) -> None:
        px = self.spec.pixel_m
        origin = np.asarray(self.spec.origin_m)
        corner = np.floor((np.minimum(a, b) - r[:, None] - origin) / px).astype(np.int64)
        span = (np.maximum(a, b) + r[:, None] - origin) / px - corner
        window = int(np.ceil(span.max())) + 1
        steps = np.arange(window)
        col = corner[:, 0, None, None] + steps[None, None, :]
        row = corner[:, 1, None, None] + steps[None, :, None]
        qx = origin[0] + col * px - a[:, 0, None, None]
        qy = origin[1] + row * px - a[:, 1, None, None]
        d = b - a
        len2 = np.maximum(np.einsum("ij,ij->i", d, d), 1e-30)
        t = (qx * d[:, 0, None, None] + qy * d[:, 1, None, None]) / len2[:, None, None]
        np.clip(t, 0.0, 1.0, out=t)
        ex = qx - t * d[:, 0, None, None]
        ey = qy - t * d[:, 1, None, None]
        rows, cols = self.spec.shape
        inside = (ex * ex + ey * ey <= (r * r)[:, None, None]) & (row >= 0) & (row < rows)
        inside &= (col >= 0) & (col < cols)
        rr = np.broadcast_to(row, inside.shape)[inside]
        cc = np.broadcast_to(col, inside.shape)[inside]
        self.pixels[rr, cc] = True


def _split_long(
    a: FloatArray, b: FloatArray, r: FloatArray, pixel_m: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Cut segments longer than the footprint into pieces so paint windows stay small."""
    keep = r > 0.0
    a, b, r = a[keep], b[keep], r[keep]
    if a.shape[0] == 0:
        return a, b, r
    piece = np.maximum(2.0 * r, 4.0 * pixel_m)
    length = np.hypot(*(b - a).T)
    count = np.maximum(1, np.ceil(length / piece)).astype(np.int64)
    if bool(np.all(count == 1)):
        return a, b, r
    owner = np.repeat(np.arange(a.shape[0]), count)
    first = np.cumsum(count) - count
    k = np.arange(owner.shape[0]) - first[owner]
    frac0 = (k / count[owner])[:, None]
    frac1 = ((k + 1) / count[owner])[:, None]
    d = (b - a)[owner]
    return a[owner] + frac0 * d, a[owner] + frac1 * d, r[owner]


def iou(written: BoolArray, target: BoolArray) -> float:
    """Intersection over union of two equally shaped rasters; 0.0 when nothing was written,
    whatever the target (both empty too: an empty union measures no agreement, and a score
    of 1.0 for a flight that wrote nothing would claim a quality nobody saw)."""
    if written.shape != target.shape:
        raise SimError(f"shapes differ: {written.shape} vs {target.shape}", field="target")
    union = int(np.count_nonzero(written | target))
    if union == 0:
        return 0.0
    return int(np.count_nonzero(written & target)) / union

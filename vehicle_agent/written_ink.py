"""The ink a flown job left on the board, as a compact picture for the public (pure).

The brush tip's sweep (its footprint width while in contact) is painted on a fine grid in the
board frame, then reduced to at most ``max_side_px`` pixels a side: a coarse pixel is ink when at
least ``min_coverage`` of it is. The result is the wire type :class:`bus.messages.WrittenInk`
(1 bit a pixel, a few kB), which the kiosk draws beside the target. It is a picture, not a score:
a job's IoU is its kind's (:meth:`vehicles.kind.VehicleKind.score`), measured on the kind's own
grid (2 mm for the brush quadrotor, 1 mm for the sponge, 4 mm for the floor marker).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from bus.messages import MAX_INK_PX, WrittenInk
from sim.ink import InkCanvas, RasterSpec
from vehicle_agent.trace import JobTrace

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

MAX_SIDE_PX = 160
"""Default pixels along the longer side (160 x 160 pixels: 3.2 kB of bits)."""
SUPERSAMPLE = 4
"""Fine pixels per coarse pixel along each side while painting."""
MIN_COVERAGE = 0.25
"""Share of a coarse pixel that must be inked for it to show as ink."""
PAD_FRACTION = 0.1
"""Border around the writing area kept in the picture, as a share of its longer side (ink a
little outside the area shows; ink further out is cut off)."""


def ink_extent_m(writing_area_m: tuple[float, float]) -> tuple[float, float, float, float]:
    """``(x_min, y_min, x_max, y_max)`` in [m] of the pictured part of the board: the writing
    area (centred on the board frame's origin) with a border of :data:`PAD_FRACTION`."""
    width_m, height_m = writing_area_m
    if not (width_m > 0.0 and height_m > 0.0):
        raise ValueError(f"writing_area_m {writing_area_m} must be positive")
    pad = PAD_FRACTION * max(width_m, height_m)
    return (-0.5 * width_m - pad, -0.5 * height_m - pad, 0.5 * width_m + pad, 0.5 * height_m + pad)


def written_ink(
    tip_xy_m_board: FloatArray,
    width_m: FloatArray,
    contact: BoolArray,
    writing_area_m: tuple[float, float],
    *,
    max_side_px: int = MAX_SIDE_PX,
) -> WrittenInk:
    """The written-ink raster of brush tip samples.

    ``tip_xy_m_board`` (n, 2): tip positions in the board frame [m]; ``width_m`` (n,): painted
    footprint diameter [m]; ``contact`` (n,): the brush touched the board. Consecutive touching
    samples paint the swept capsule between them (:class:`sim.ink.InkCanvas`).
    """
    if not 1 <= max_side_px <= MAX_INK_PX:
        raise ValueError(f"max_side_px {max_side_px} must be within 1..{MAX_INK_PX}")
    x_min, y_min, x_max, y_max = ink_extent_m(writing_area_m)
    pixel_m = max(x_max - x_min, y_max - y_min) / max_side_px
    cols = min(max_side_px, math.ceil((x_max - x_min) / pixel_m - 1e-9))
    rows = min(max_side_px, math.ceil((y_max - y_min) / pixel_m - 1e-9))
    x_max, y_max = x_min + cols * pixel_m, y_min + rows * pixel_m
    fine_m = pixel_m / SUPERSAMPLE
    spec = RasterSpec(
        origin_m=(x_min + 0.5 * fine_m, y_min + 0.5 * fine_m),
        pixel_m=fine_m,
        shape=(rows * SUPERSAMPLE, cols * SUPERSAMPLE),
    )
    canvas = InkCanvas(spec)
    canvas.paint_path(
        np.asarray(tip_xy_m_board, dtype=np.float64).reshape(-1, 2),
        np.asarray(width_m, dtype=np.float64).reshape(-1),
        np.asarray(contact, dtype=np.bool_).reshape(-1),
    )
    coverage = canvas.pixels.reshape(rows, SUPERSAMPLE, cols, SUPERSAMPLE).mean(axis=(1, 3))
    top_first = (coverage >= MIN_COVERAGE)[::-1]
    return WrittenInk(
        width_px=cols,
        height_px=rows,
        extent_m_board=(x_min, y_min, x_max, y_max),
        bits=np.packbits(top_first.ravel()).tobytes(),
    )


def written_ink_of_trace(
    trace: JobTrace,
    to_board: Callable[[FloatArray], FloatArray],
    writing_area_m: tuple[float, float],
) -> WrittenInk | None:
    """The ink of a flown job (None when the backend does not report its brush tip, width and
    contact). ``to_board``: world ENU points (n, 3) -> board-frame points (n, 2) in [m], e.g.
    ``BoardFrame.to_board``. The ink laid (``ink_width_m``, 0 without contact) says where the
    brush painted: a touching sample of no width paints nothing (:meth:`InkCanvas.paint_path`)."""
    flown = trace.flown
    if not trace.pen_known or flown.t_s.shape[0] == 0:
        return None
    width = flown.ink_width_m
    return written_ink(to_board(flown.writing_point_m_enu), width, width > 0.0, writing_area_m)


def ink_pixels(ink: WrittenInk) -> BoolArray:
    """The raster of ``ink`` as a (height_px, width_px) array, row 0 at the top."""
    count = ink.width_px * ink.height_px
    bits = np.unpackbits(np.frombuffer(ink.bits, dtype=np.uint8), count=count)
    return bits.astype(np.bool_).reshape(ink.height_px, ink.width_px)

"""How well a flight wrote: tracking errors of the brush and ink intersection over union.

Read from the kinds' one trace format (:class:`vehicles.kind.FlownWriting`) of one vehicle: a batch
flight's (:func:`vehicles.quadrotor_brush.trace.flown_of`) or the live agent's. Without a logged
body axis (``extra["body_z_enu"]``; the live agent logs none) the brush axis from the tip
(``extra["tip_m_enu"]``, else the writing point) up to the body stands for it; without a base
position the writing point stands for the body.

Tracking is measured at the *writing point*: the point of the brush axis one lever (reference point
to tip at nominal press) below the vehicle reference point, ``p - lever * (n - e_z)`` with ``n``
the body z axis. Level, it is the vehicle reference point itself (what Phang 2015 Fig. 12 plots);
tilted, it moves with the brush. Its reference is the planned position.

Ink (Guo 2024 section VII): the written raster is what the brush footprint painted while touching
(``ink_width_m`` above 0); the target raster is the whole plan's pen-down path painted at the
nominal width, however much of it was flown (a job aborted at 30 % scores what it wrote against
the whole character). Both at ``pixel_m``.

A figure of the pen-down part of a flight whose pen never came down is None: not measured.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import NDArray

from planner.samples import TrajectorySamples
from sim.ink import InkCanvas, RasterSpec, iou
from vehicles.kind import FlownWriting
from vehicles.quadrotor_brush.brush import writing_point
from vehicles.quadrotor_brush.params import BrushParams

FloatArray = NDArray[np.float64]

_UP = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class FlightMetrics:
    """Scores of one vehicle's flight."""

    rmse_pen_down_m: float | None
    """RMS 3-D writing-point error while the reference writes, [m] (None: it never wrote)."""
    rmse_m: float
    """RMS 3-D writing-point error over the whole flight, [m]."""
    max_error_m: float
    """Largest 3-D writing-point error over the flight, [m]."""
    max_error_pen_down_m: float | None
    """Largest 3-D writing-point error while writing, [m] (None: it never wrote)."""
    rmse_pen_down_xy_m: float | None
    """RMS horizontal writing-point error while writing (what moves the ink), [m]."""
    rmse_pen_down_z_m: float | None
    """RMS height error while writing (what changes the press, hence the width), [m]."""
    vehicle_rmse_pen_down_m: float | None
    """RMS 3-D error of the vehicle reference point itself while writing, [m]."""
    iou: float
    """Intersection over union of written and target ink (the whole plan's)."""
    ink_intersection_ratio: float
    """|written and target| / |target| (Guo 2024 reports 0.79)."""
    ink_union_ratio: float
    """|written or target| / |target| (Guo 2024 reports 1.35)."""
    sim_time_s: float
    """Simulated flight time, [s]."""

    def to_json_dict(self) -> dict[str, float | None]:
        """Plain dict of floats (None: not measured)."""
        return {k: None if v is None else float(v) for k, v in asdict(self).items()}


@dataclass(frozen=True)
class InkResult:
    """Written and target rasters of one vehicle on the same grid."""

    written: InkCanvas
    """What the brush painted."""
    target: InkCanvas
    """The whole plan's pen-down path at nominal width."""

    @property
    def iou(self) -> float:
        """Intersection over union."""
        return iou(self.written.pixels, self.target.pixels)


def body_of(flown: FlownWriting) -> FloatArray:
    """(K, 3) vehicle reference point in [m], ENU (the writing point where none was logged)."""
    return flown.base_m_enu if flown.base_m_enu is not None else flown.writing_point_m_enu


def tip_of(flown: FlownWriting) -> FloatArray:
    """(K, 3) brush tip in [m], ENU (the writing point where none was logged)."""
    tip: FloatArray = flown.extra.get("tip_m_enu", flown.writing_point_m_enu)
    return tip


def body_z_of(flown: FlownWriting) -> FloatArray:
    """(K, 3) body z axis (the brush axis, upwards): logged, or from the tip up to the body
    (straight up where they meet)."""
    body_z: FloatArray | None = flown.extra.get("body_z_enu")
    if body_z is not None:
        return body_z
    axis = body_of(flown) - tip_of(flown)
    length = np.linalg.norm(axis, axis=1, keepdims=True)
    derived: FloatArray = np.where(length > 1e-9, axis / np.maximum(length, 1e-9), _UP)
    return derived


def writing_point_error(flown: FlownWriting, brush: BrushParams) -> FloatArray:
    """Writing-point error per tick, shape (K, 3), [m]."""
    point = writing_point(body_of(flown), body_z_of(flown), brush.write_height_m)
    error: FloatArray = point - flown.reference_m_enu
    return error


def ink_result(
    flown: FlownWriting,
    brush: BrushParams,
    planned: TrajectorySamples,
    *,
    pixel_m: float = 0.001,
) -> InkResult:
    """Paint the written ink of ``flown`` and the target ink of the whole plan ``planned`` (the
    writing point's reference, world ENU)."""
    pen = planned.pen_down
    contact = flown.ink_width_m > 0.0
    ref_xy = planned.position_m_enu[:, :2]
    tip_xy = tip_of(flown)[:, :2]
    covered = np.concatenate((ref_xy[pen], tip_xy[contact], ref_xy[:1]))
    spec = RasterSpec.covering(covered, pixel_m=pixel_m, margin_m=brush.nominal_width_m + 0.01)
    target = InkCanvas(spec)
    target.paint_path(ref_xy, np.full(pen.shape, brush.nominal_width_m), pen)
    written = InkCanvas(spec)
    written.paint_path(tip_xy, flown.ink_width_m, contact)
    return InkResult(written, target)


def _rms(squares: FloatArray) -> float | None:
    """Root of the mean of ``squares``; None for none (not measured)."""
    return float(np.sqrt(np.mean(squares))) if squares.size else None


def flight_metrics(
    flown: FlownWriting,
    brush: BrushParams,
    planned: TrajectorySamples,
    *,
    pixel_m: float = 0.001,
    ink: InkResult | None = None,
) -> FlightMetrics:
    """Scores of the flight of ``brush`` against the whole plan ``planned`` (paints the ink
    unless ``ink`` is given)."""
    err = writing_point_error(flown, brush)
    pen = flown.pen_down
    sq = np.sum(err * err, axis=1)
    veh = body_of(flown) - flown.reference_m_enu
    ink = ink if ink is not None else ink_result(flown, brush, planned, pixel_m=pixel_m)
    target = max(int(np.count_nonzero(ink.target.pixels)), 1)
    both = int(np.count_nonzero(ink.written.pixels & ink.target.pixels))
    either = int(np.count_nonzero(ink.written.pixels | ink.target.pixels))
    t_s = flown.t_s
    return FlightMetrics(
        rmse_pen_down_m=_rms(sq[pen]),
        rmse_m=float(np.sqrt(np.mean(sq))) if sq.size else 0.0,
        max_error_m=float(np.sqrt(sq.max())) if sq.size else 0.0,
        max_error_pen_down_m=float(np.sqrt(sq[pen].max())) if pen.any() else None,
        rmse_pen_down_xy_m=_rms(np.sum(err[pen, :2] ** 2, axis=1)),
        rmse_pen_down_z_m=_rms(err[pen, 2] ** 2),
        vehicle_rmse_pen_down_m=_rms(np.sum(veh[pen] ** 2, axis=1)),
        iou=ink.iou,
        ink_intersection_ratio=both / target,
        ink_union_ratio=either / target,
        sim_time_s=float(t_s[-1] - t_s[0]) if t_s.size else 0.0,
    )

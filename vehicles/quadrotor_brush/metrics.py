"""How well a flight wrote: tracking errors of the brush and ink intersection over union.

Tracking is measured at the *writing point*: the point of the brush axis one lever (reference point
to tip at nominal press) below the vehicle reference point, ``p - lever * (n - e_z)`` with ``n``
the body z axis. Level, it is the vehicle reference point itself (what Phang 2015 Fig. 12 plots);
tilted, it moves with the brush. Its reference is the planned position.

Ink (Guo 2024 section VII): the written raster is what the brush footprint painted while touching;
the target raster is the planned pen-down path painted at the nominal width. Both at ``pixel_m``.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import NDArray

from sim.ink import InkCanvas, RasterSpec, iou
from vehicles.quadrotor_brush.flight import FlightLog

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class FlightMetrics:
    """Scores of one vehicle's flight."""

    rmse_pen_down_m: float
    """RMS 3-D writing-point error while the reference writes, [m]."""
    rmse_m: float
    """RMS 3-D writing-point error over the whole flight, [m]."""
    max_error_m: float
    """Largest 3-D writing-point error over the flight, [m]."""
    max_error_pen_down_m: float
    """Largest 3-D writing-point error while writing, [m]."""
    rmse_pen_down_xy_m: float
    """RMS horizontal writing-point error while writing (what moves the ink), [m]."""
    rmse_pen_down_z_m: float
    """RMS height error while writing (what changes the press, hence the width), [m]."""
    vehicle_rmse_pen_down_m: float
    """RMS 3-D error of the vehicle reference point itself while writing, [m]."""
    iou: float
    """Intersection over union of written and target ink."""
    ink_intersection_ratio: float
    """|written and target| / |target| (Guo 2024 reports 0.79)."""
    ink_union_ratio: float
    """|written or target| / |target| (Guo 2024 reports 1.35)."""
    sim_time_s: float
    """Simulated flight time, [s]."""

    def to_json_dict(self) -> dict[str, float]:
        """Plain dict of floats."""
        return {k: float(v) for k, v in asdict(self).items()}


@dataclass(frozen=True)
class InkResult:
    """Written and target rasters of one vehicle on the same grid."""

    written: InkCanvas
    """What the brush painted."""
    target: InkCanvas
    """The planned pen-down path at nominal width."""

    @property
    def iou(self) -> float:
        """Intersection over union."""
        return iou(self.written.pixels, self.target.pixels)


def writing_point_error(log: FlightLog) -> FloatArray:
    """Writing-point error per tick and vehicle, shape (K, N, 3), [m]."""
    up = np.array([0.0, 0.0, 1.0])
    point = log.position_m_enu - log.brush_lever_m * (log.body_z_enu - up)
    error: FloatArray = point - log.reference_position_m_enu
    return error


def ink_result(log: FlightLog, vehicle: int = 0, *, pixel_m: float = 0.001) -> InkResult:
    """Paint the written and the target ink of one vehicle."""
    pen = log.pen_down[:, vehicle]
    contact = log.brush_contact[:, vehicle]
    ref_xy = log.reference_position_m_enu[:, vehicle, :2]
    tip_xy = log.tip_m_enu[:, vehicle, :2]
    covered = np.concatenate((ref_xy[pen], tip_xy[contact], ref_xy[:1]))
    spec = RasterSpec.covering(covered, pixel_m=pixel_m, margin_m=log.nominal_width_m + 0.01)
    target = InkCanvas(spec)
    target.paint_path(ref_xy, np.full(pen.shape, log.nominal_width_m), pen)
    written = InkCanvas(spec)
    written.paint_path(tip_xy, log.brush_width_m[:, vehicle], contact)
    return InkResult(written, target)


def _rms(values: FloatArray) -> float:
    return float(np.sqrt(np.mean(values))) if values.size else 0.0


def flight_metrics(
    log: FlightLog, vehicle: int = 0, *, pixel_m: float = 0.001, ink: InkResult | None = None
) -> FlightMetrics:
    """Scores of vehicle ``vehicle`` (paints the ink unless ``ink`` is given)."""
    err = writing_point_error(log)[:, vehicle]
    pen = log.pen_down[:, vehicle]
    sq = np.sum(err * err, axis=1)
    veh = log.position_m_enu[:, vehicle] - log.reference_position_m_enu[:, vehicle]
    ink = ink if ink is not None else ink_result(log, vehicle, pixel_m=pixel_m)
    target = max(int(np.count_nonzero(ink.target.pixels)), 1)
    both = int(np.count_nonzero(ink.written.pixels & ink.target.pixels))
    either = int(np.count_nonzero(ink.written.pixels | ink.target.pixels))
    return FlightMetrics(
        rmse_pen_down_m=_rms(sq[pen]),
        rmse_m=_rms(sq),
        max_error_m=float(np.sqrt(sq.max())) if sq.size else 0.0,
        max_error_pen_down_m=float(np.sqrt(sq[pen].max())) if pen.any() else 0.0,
        rmse_pen_down_xy_m=_rms(np.sum(err[pen, :2] ** 2, axis=1)),
        rmse_pen_down_z_m=_rms(err[pen, 2] ** 2),
        vehicle_rmse_pen_down_m=_rms(np.sum(veh[pen] ** 2, axis=1)),
        iou=ink.iou,
        ink_intersection_ratio=both / target,
        ink_union_ratio=either / target,
        sim_time_s=float(log.t_s[-1] - log.t_s[0]) if log.t_s.size else 0.0,
    )

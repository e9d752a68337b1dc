"""Writing on the floor: a body-velocity tracking controller turning the marker's reference (planned
by :mod:`vehicles.omni_wheel.floor_plan`) into wheel references in MuJoCo, a marker on a lift, ink
on the floor's raster.

Drive: each control tick the marker's position is measured (floor localisation, millimetre noise)
and the commanded marker velocity is the reference's plus a proportional correction; it is moved
to the middle axle (the proposed method's reference point), turned into the body frame and fed to
:func:`wheel_control.proposed_references` with the sensed body configuration, so the same
controller climbs steps on the way. Heading is held by a proportional yaw-rate command.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from sim.ink import InkCanvas, RasterSpec, iou
from vehicles.kind import FlownWriting, WritingPlan, WritingScore
from vehicles.omni_wheel.climb import configuration_of, wheel_ratios
from vehicles.omni_wheel.floor_plan import OmniSettings
from vehicles.omni_wheel.sim import OmniWorld
from vehicles.omni_wheel.wheel_control import proposed_references

FloatArray = NDArray[np.float64]


def _heading_rad(rotation: FloatArray) -> float:
    return math.atan2(float(rotation[1, 0]), float(rotation[0, 0]))


class FloorWriter:
    """One ground writer driving a writing point reference on a floor, tick by tick."""

    def __init__(
        self, settings: OmniSettings, start_pen_m_enu: FloatArray, *, seed: int = 0
    ) -> None:
        self.settings = settings
        offset = settings.pen_offset_m()
        x, y = float(start_pen_m_enu[0]) - offset, float(start_pen_m_enu[1])
        floor = settings.terrain.height_at_m(x)
        self.world = OmniWorld(
            settings.geometry, settings.terrain, ((x, y, floor, 0.0),), seed=seed,
            control_dt_s=settings.control_dt_s,
        )  # fmt: skip
        self._rng = np.random.default_rng(seed + 7919)
        self._pen_timer_s = 0.0
        self.pen_is_down = False
        self.last_refs_radps = np.zeros(7)
        """The wheel references of the last tick in [rad/s]."""
        self.measured_marker_xy = np.asarray(start_pen_m_enu[:2], dtype=np.float64)
        """The marker's position in [m] as the last tick measured it (floor localisation)."""

    def tick(
        self, position_m_enu: FloatArray, velocity_mps_enu: FloatArray, pen_down: bool
    ) -> None:
        """Track the marker reference for one control period; move the lift towards ``pen_down``."""
        s = self.settings
        truth = self.world.truth(0)
        sensed = self.world.sense(0)
        pen_xy = truth.pen_m_enu[:2] + self._rng.normal(0.0, s.position_noise_m, 2)
        self.measured_marker_xy = pen_xy
        heading = _heading_rad(truth.rotation) + float(self._rng.normal(0.0, s.heading_noise_rad))
        v_world = np.asarray(velocity_mps_enu[:2]) + s.position_gain_per_s * (
            np.asarray(position_m_enu[:2]) - pen_xy
        )
        yaw_rate = -s.heading_gain_per_s * heading
        c, sn = math.cos(heading), math.sin(heading)
        v_body = np.array(
            [c * v_world[0] + sn * v_world[1], -sn * v_world[0] + c * v_world[1], 0.0]
        )
        v_body[1] -= yaw_rate * s.pen_offset_m()  # pen velocity -> middle axle velocity
        refs = proposed_references(v_body, configuration_of(sensed, yaw_rate), s.geometry)
        self.last_refs_radps = refs.rate_radps
        self.world.step(refs.rate_radps[None, :])
        want = 1.0 if pen_down else -1.0
        self._pen_timer_s = float(
            np.clip(self._pen_timer_s + want * s.control_dt_s, 0.0, s.lift_delay_s)
        )
        self.pen_is_down = self._pen_timer_s >= s.lift_delay_s - 1e-9

    def marker_m_enu(self) -> FloatArray:
        """True marker point on the floor in [m], world ENU."""
        return self.world.truth(0).pen_m_enu


def drive_plan(plan: WritingPlan, settings: OmniSettings, *, seed: int = 0) -> FlownWriting:
    """Drive ``plan`` from rest at its first point to its end (batch)."""
    samples = plan.samples
    writer = FloorWriter(settings, samples.position_m_enu[0], seed=seed)
    dt = settings.control_dt_s
    n = math.floor(samples.duration_s / dt) + 1
    t = np.arange(n, dtype=np.float64) * dt
    ref = np.column_stack(
        [np.interp(t, samples.t_s, samples.position_m_enu[:, i]) for i in range(3)]
    )
    vel = np.column_stack(
        [np.interp(t, samples.t_s, samples.velocity_mps_enu[:, i]) for i in range(3)]
    )
    pen = samples.pen_down[np.clip(np.searchsorted(samples.t_s, t, side="right") - 1, 0, None)]
    point = np.empty((n, 3))
    base = np.empty((n, 3))
    inked = np.zeros(n, dtype=bool)
    slip, rotation_error = np.empty((n, 7)), np.empty((n, 7))
    for k in range(n):
        writer.tick(ref[k], vel[k], bool(pen[k]))
        truth = writer.world.truth(0)
        point[k], base[k] = truth.pen_m_enu, truth.base_m_enu
        slip[k], rotation_error[k] = wheel_ratios(truth, writer.last_refs_radps, settings.geometry)
        inked[k] = writer.pen_is_down
    width = np.where(inked, settings.marker_width_m, 0.0)
    return FlownWriting(
        t_s=np.asarray(t + dt, dtype=np.float64),
        reference_m_enu=ref,
        writing_point_m_enu=point,
        pen_down=pen,
        ink_width_m=width,
        base_m_enu=base,
        extra={"slip": slip, "rotation_error": rotation_error},
    )


def score_floor(plan: WritingPlan, flown: FlownWriting, marker_width_m: float) -> WritingScore:
    """RMSE of the marker against its reference (pen down, all) and IoU of written against planned
    ink (the whole plan's pen-down reference at the marker's width, however much of it was
    flown), on the floor raster. The pen-down figures of a run whose pen never came down are
    not measured: None, and no ``max_error_pen_down_m``."""
    err = np.linalg.norm(flown.writing_point_m_enu[:, :2] - flown.reference_m_enu[:, :2], axis=1)
    pen = flown.pen_down
    planned = plan.samples
    ref_xy = plan.surface.to_surface(planned.position_m_enu)
    point_xy = plan.surface.to_surface(flown.writing_point_m_enu)
    down = planned.pen_down
    spec = RasterSpec.covering(np.vstack([ref_xy[down], ref_xy[:1]]), pixel_m=0.004, margin_m=0.1)
    target, written = InkCanvas(spec), InkCanvas(spec)
    target.paint_path(ref_xy, np.full(down.shape, marker_width_m), down)
    written.paint_path(point_xy, flown.ink_width_m, flown.ink_width_m > 0.0)
    return WritingScore(
        rmse_pen_down_m=float(np.sqrt(np.mean(err[pen] ** 2))) if pen.any() else None,
        rmse_m=float(np.sqrt(np.mean(err**2))),
        max_error_m=float(err.max()),
        iou=iou(written.pixels, target.pixels) if down.any() else None,
        extra={"max_error_pen_down_m": float(err[pen].max())} if pen.any() else {},
    )

"""Writing on the floor: the stroke pipeline in the floor plane, a body-velocity tracking controller
turning the reference into wheel references, a marker on a lift, ink on the floor's raster.

Plan: ``planner.pipeline.plan_strokes`` on the floor area (split-and-merge, minimum-jerk B-spline
with acceleration limits, time re-segmentation) with the ground writer's limits. The planner's
height axis only carries the pen: writing height and clearance are a virtual lift; the reference
handed on lies on the floor. The vehicle is holonomic and keeps its heading (world east): no
heading constraint enters the plan.

Drive: each control tick the marker's position is measured (floor localisation, millimetre noise)
and the commanded marker velocity is the reference's plus a proportional correction; it is moved
to the middle axle (the proposed method's reference point), turned into the body frame and fed to
:func:`wheel_control.proposed_references` with the sensed body configuration, so the same
controller climbs steps on the way. Heading is held by a proportional yaw-rate command.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from planner.board import BoardFrame
from planner.limits import GRAVITY_MPS2, VehicleLimits
from planner.options import PlanOptions
from planner.pipeline import plan_strokes
from planner.samples import TrajectorySamples
from sim.ink import InkCanvas, RasterSpec, iou
from vehicles.kind import FlownWriting, StrokeInput, WritingPlan, WritingScore
from vehicles.omni_wheel.climb import configuration_of, wheel_ratios
from vehicles.omni_wheel.geometry import OmniGeometry
from vehicles.omni_wheel.sim import OmniWorld
from vehicles.omni_wheel.terrain import Terrain
from vehicles.omni_wheel.wheel_control import proposed_references
from vehicles.surface import Surface

FloatArray = NDArray[np.float64]

RUBBER_ROLLERS = OmniGeometry(friction_static=1.0, friction_dynamic=0.9)
"""The prototype with rubber rollers: Table 1's 0.3 cannot lift a wheel onto a 50 mm step in
MuJoCo (tests/test_ground_sim.py), so the writer climbs on rubber."""
VIRTUAL_WRITE_HEIGHT_M = 0.05
"""Planner height of the pen-down reference above the floor in [m] (the pen axis only)."""
VIRTUAL_CLEARANCE_M = 0.03
"""Planner height added with the pen up in [m]."""


@dataclass(frozen=True)
class OmniSettings:
    """Everything the ground writer needs besides the strokes. SI units."""

    geometry: OmniGeometry = RUBBER_ROLLERS
    """The vehicle."""
    accel_max_mps2: tuple[float, float] = (0.25, 0.15)
    """Largest planned acceleration in [m/s^2] along the body's x and y (y is driven by the one
    sideways wheel: less traction)."""
    speed_max_mps: float = 0.2
    """Largest planned marker speed in [m/s] (below V0, which bounds every wheel)."""
    marker_width_m: float = 0.04
    """Width in [m] of the marker's line."""
    lift_delay_s: float = 0.05
    """Time in [s] the lift takes to put the marker down or up."""
    position_noise_m: float = 0.001
    """Standard deviation in [m] of the marker's measured position (floor localisation)."""
    heading_noise_rad: float = 0.002
    """Standard deviation in [rad] of the measured heading."""
    position_gain_per_s: float = 3.0
    """Proportional gain in [1/s] of the marker position correction."""
    heading_gain_per_s: float = 2.0
    """Proportional gain in [1/s] of the heading correction."""
    terrain: Terrain = field(default_factory=Terrain)
    """Floor with its steps (world x)."""
    control_dt_s: float = 0.01
    """Control period in [s]."""

    def pen_offset_m(self) -> float:
        """x in [m] of the marker ahead of the middle axle (under the front linkage's middle)."""
        g = self.geometry
        return g.joint1_x_m + 0.5 * g.front_link_m


DEFAULT_SETTINGS = OmniSettings()
"""The ground writer's defaults."""


def plan_floor(
    strokes: Sequence[StrokeInput], surface: Surface, settings: OmniSettings
) -> WritingPlan:
    """Plan writing ``strokes`` on the floor area ``surface`` (raises ``PlannerError``)."""
    g = settings.geometry
    mass = g.front_mass_kg + g.rear_mass_kg
    ax, ay = settings.accel_max_mps2
    limits = VehicleLimits(
        a_max_mps2=(ax, ay, 0.5),
        v_max_mps=settings.speed_max_mps,
        mass_kg=mass,
        thrust_max_n=2.0 * mass * GRAVITY_MPS2,
    )
    yaw = math.atan2(surface.x_axis_enu[1], surface.x_axis_enu[0])
    board = BoardFrame(center_m_enu=surface.origin_m_enu, yaw_rad=yaw)
    options = PlanOptions(
        limits=limits,
        board=board,
        write_height_m=VIRTUAL_WRITE_HEIGHT_M,
        clearance_m=VIRTUAL_CLEARANCE_M,
        fit_tolerance_m=0.02,
    )
    traj = plan_strokes([np.asarray(s.xy_m, dtype=np.float64) for s in strokes], options)
    raw = traj.sample(100.0)
    on_floor = raw.position_m_enu.copy()
    on_floor[:, 2] = surface.origin_m_enu[2]
    flat = np.column_stack([raw.velocity_mps_enu[:, :2], np.zeros(raw.t_s.shape[0])])
    acc = np.column_stack([raw.acceleration_mps2_enu[:, :2], np.zeros(raw.t_s.shape[0])])
    samples = TrajectorySamples(raw.t_s, on_floor, flat, acc, raw.pen_down)
    report = traj.feasibility
    feasibility = {
        "peak_speed_mps": report.peak_speed_mps,
        "v_max_mps": report.v_max_mps,
        "peak_accel_mps2": list(report.peak_accel_mps2[:2]),
        "accel_max_mps2": [ax, ay],
        "duration_s": traj.duration_s,
        **{k: v for k, v in traj.info.items() if isinstance(v, int | float | str)},
    }
    return WritingPlan(
        samples=samples, strokes=tuple(strokes), surface=surface, feasibility=feasibility
    )


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
    ink (the pen-down reference at the marker's width), on the floor raster."""
    err = np.linalg.norm(flown.writing_point_m_enu[:, :2] - flown.reference_m_enu[:, :2], axis=1)
    pen = flown.pen_down
    ref_xy = plan.surface.to_surface(flown.reference_m_enu)
    point_xy = plan.surface.to_surface(flown.writing_point_m_enu)
    spec = RasterSpec.covering(np.vstack([ref_xy[pen], ref_xy[:1]]), pixel_m=0.004, margin_m=0.1)
    target, written = InkCanvas(spec), InkCanvas(spec)
    target.paint_path(ref_xy, np.full(pen.shape, marker_width_m), pen)
    written.paint_path(point_xy, flown.ink_width_m, flown.ink_width_m > 0.0)
    return WritingScore(
        rmse_pen_down_m=float(np.sqrt(np.mean(err[pen] ** 2))) if pen.any() else 0.0,
        rmse_m=float(np.sqrt(np.mean(err**2))),
        max_error_m=float(err.max()),
        iou=iou(written.pixels, target.pixels) if pen.any() else None,
        extra={"max_error_pen_down_m": float(err[pen].max()) if pen.any() else 0.0},
    )

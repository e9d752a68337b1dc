"""The ground writer's settings and its plan on the floor: the stroke pipeline in the floor plane.
No MuJoCo here (``writing`` drives the plan in it), so planning a ground job (a kiosk preview, an
orchestrator's estimate) loads only the planner.

Plan: ``planner.pipeline.plan_strokes`` on the floor area (split-and-merge, minimum-jerk B-spline
with acceleration limits, time re-segmentation) with the ground writer's limits. The planner's
height axis only carries the pen: writing height and clearance are a virtual lift; the reference
handed on lies on the floor. The vehicle is holonomic and keeps its heading (world east): no
heading constraint enters the plan.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from planner.board import BoardFrame
from planner.limits import GRAVITY_MPS2, VehicleLimits
from planner.options import PlanOptions
from planner.pipeline import plan_strokes
from planner.samples import TrajectorySamples
from vehicles.kind import StrokeInput, WritingPlan
from vehicles.omni_wheel.geometry import OmniGeometry
from vehicles.omni_wheel.terrain import Terrain
from vehicles.surface import Surface

RUBBER_ROLLERS = OmniGeometry(friction_static=1.0, friction_dynamic=0.9)
"""The prototype with rubber rollers: our analogue of the experiment's vehicle (section 3.3), not
a value of the paper. Table 1's 0.3 cannot lift any axle up a riser (``statics``: the front
axle needs 45 N, the riser's friction gives at most 15 N) nor a wheel onto a 50 mm step in
MuJoCo (tests/test_ground_sim.py); the prototype climbed 152 mm, so its rollers gripped
better than 0.3. 1.0 static, 0.9 sliding: rubber on a dry hard floor, a generic figure (the
paper names no material); bench_ground's sensitivity table runs 0.8 and 1.2 too."""
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

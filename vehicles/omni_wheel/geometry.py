"""The ground writer's prototype (Chugo et al., Table 1) and its wheel layout.

Body frame of the rear part (the paper's coordinate system {4}): origin on the middle axle line at
axle height, x forward (the climbing direction), y to the left, z up. The front part hangs on
free joint 1 (pitch, with a roll joint at the same point) at axle height, ``joint1_x_m`` ahead of
the middle axle; its front axle is ``front_link_m`` ahead of the joint.

Seven actuated wheels: front-left, front-centre, front-right on the front part's axle line (the
centre one drives sideways, its axle along x); middle-left, middle-right and rear-left, rear-right
on the rear part. The six side wheels drive along x; together with the sideways wheel the seven
give every body twist (vx, vy, yaw rate) on the flat. The sideways wheel sits on the front axle
line so that it rises with the front wheels when they climb a step and never meets the step face.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

WHEEL_NAMES = (
    "front_left",
    "front_centre",
    "front_right",
    "middle_left",
    "middle_right",
    "rear_left",
    "rear_right",
)
"""The seven wheels, in the order of every per-wheel array of this room."""
FRONT_PART = np.array([True, True, True, False, False, False, False])
"""Which wheels hang on the front part (the others are on the rear part)."""
WHEEL_GROUP = ("front", "front", "front", "middle", "middle", "rear", "rear")
"""Front / middle / rear group of each wheel (as the paper's Table 2 reports them)."""


@dataclass(frozen=True)
class OmniGeometry:
    """Dimensions and masses of the prototype (Table 1), SI units."""

    wheel_radius_m: float = 0.066
    """Wheel radius in [m] (132 mm diameter)."""
    front_middle_m: float = 0.255
    """Distance in [m] from the front axle to the middle axle."""
    middle_rear_m: float = 0.215
    """Distance in [m] from the middle axle to the rear axle."""
    front_link_m: float = 0.195
    """Length in [m] of the front linkage: free joint 1 to the front axle."""
    rear_link_m: float = 0.400
    """Length in [m] of the rear part's frame (tail to nose)."""
    front_mass_kg: float = 7.8
    """Mass in [kg] of the front part, its wheels included."""
    rear_mass_kg: float = 13.8
    """Mass in [kg] of the rear part, its wheels included."""
    half_track_m: float = 0.15
    """Lateral distance in [m] from the centre line to the left and right wheels."""
    running_speed_mps: float = 0.25
    """V0 in [m/s], the running speed and the bound on every wheel's speed."""
    friction_static: float = 0.3
    """Static friction coefficient of the rollers on the ground."""
    friction_dynamic: float = 0.25
    """Dynamic friction coefficient (MuJoCo has one coefficient: the static one is used, the
    dynamic one is reported with it)."""
    rollers_per_wheel: int = 12
    """Free rollers on each wheel's rim."""
    rear_frame_com_x_m: float = -0.140
    """x in [m] of the rear frame's mass centre (its wheels excluded) in the rear part's frame.
    The paper's figures are not in our copy; the reading is the middle of the rear part's
    400 mm frame (Table 1), which ends at free joint 1, 0.060 m ahead of the middle axle:
    0.060 - 0.200. The other reading, midway between middle and rear axles (-0.1075), is a row
    of bench_ground's sensitivity table."""
    front_frame_com_m: float = 0.0975
    """Distance in [m] of the front frame's mass centre (its wheels excluded) ahead of free
    joint 1: the middle of the front part's 195 mm linkage (Table 1), the same reading."""
    frame_clearance_m: float = 0.050
    """Height in [m] of the frames' underside above the axle line (the body's collision
    geometry, ``model``). Not in the text; its lower bound follows from the prototype's 152 mm
    climb (section 3.3): the frames cleared that step's edge, both the rear frame with its rear
    wheels at the riser and the front linkage pitched up over it with joint 1 at the riser
    (``statics.min_frame_clearance_m``: 49 mm), rounded up to the next 5 mm."""
    motor_torque_max_nm: float = 3.6
    """Largest torque in [N m] a wheel's motor and gear give. Not in the paper; the basis is the
    quasi-static torque its 152 mm climb needs (``statics.required_torque_nm``): the middle
    wheels lift their axle's load up the riser, 3.0 N m with the mass centres read above and
    3.6 N m with the other reading of the rear one. The prototype climbed it whichever reading
    is right, so its motors gave at least the larger; bench_ground's sensitivity table shows
    what the value decides."""

    @property
    def joint1_x_m(self) -> float:
        """x in [m] of free joint 1 in the rear part's frame (at axle height)."""
        return self.front_middle_m - self.front_link_m

    def wheel_positions_m(self) -> FloatArray:
        """(7, 3) wheel centres in [m] in the rear part's frame, all joints at zero."""
        w, f, r = self.half_track_m, self.front_middle_m, -self.middle_rear_m
        return np.array(
            [[f, w, 0.0], [f, 0.0, 0.0], [f, -w, 0.0], [0.0, w, 0.0], [0.0, -w, 0.0],
             [r, w, 0.0], [r, -w, 0.0]]
        )  # fmt: skip

    def drive_directions(self) -> FloatArray:
        """(7, 3) unit drive direction of each wheel in its part's frame (x, or y for the
        front-centre wheel)."""
        d = np.zeros((7, 3))
        d[:, 0] = 1.0
        d[1] = (0.0, 1.0, 0.0)
        return d

    def axle_directions(self) -> FloatArray:
        """(7, 3) unit axle of each wheel: positive spin about it rolls the wheel forward along its
        drive direction (``axle = up x drive``)."""
        return np.cross(np.array([0.0, 0.0, 1.0]), self.drive_directions())

"""Mocap as ODOMETRY: the pose and the velocity the poses imply, in each autopilot's frames (pure).

A venue's motion capture gives poses; the velocity is their difference over the capture times,
as a mocap client would derive it. ODOMETRY carries both, so the estimator fuses the velocity
too instead of building it on its accelerometer alone. Each autopilot takes other frames:

- PX4 (mavlink_receiver, v1.16): pose in MAV_FRAME_LOCAL_NED, velocity in LOCAL_NED
  (``child_frame_id``), ``estimator_type`` VISION: EKF2 fuses only what comes as vision
  (MOCAP goes to a topic it does not read);
- ArduPilot (GCS_MAVLINK::handle_odometry, 4.7): only MAV_FRAME_LOCAL_FRD with the velocity in
  MAV_FRAME_BODY_FRD (it turns it back with the message's attitude); any other pair is dropped.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Any

from vehicle_agent.backends.mavlink.frames import Vec3, euler_to_matrix, euler_to_quaternion
from vehicle_agent.backends.mavlink.params import Flavor

MAV_FRAME_LOCAL_NED = 1
MAV_FRAME_BODY_FRD = 12
MAV_FRAME_LOCAL_FRD = 20
MAV_ESTIMATOR_TYPE_VISION = 2
NAN3: Vec3 = (math.nan, math.nan, math.nan)
"""An unknown velocity (the autopilots fuse the pose alone)."""


@dataclass(frozen=True)
class OdometryFrames:
    """The frames and estimator type one autopilot accepts in ODOMETRY."""

    frame_id: int
    """MAV_FRAME of the pose."""
    child_frame_id: int
    """MAV_FRAME of the velocity."""
    estimator_type: int
    body_velocity: bool
    """The velocity goes in the body frame (FRD), not in the local NED frame."""


ODOMETRY_FRAMES: dict[Flavor, OdometryFrames] = {
    "px4": OdometryFrames(MAV_FRAME_LOCAL_NED, MAV_FRAME_LOCAL_NED, MAV_ESTIMATOR_TYPE_VISION,
                          body_velocity=False),
    "ardupilot": OdometryFrames(MAV_FRAME_LOCAL_FRD, MAV_FRAME_BODY_FRD,
                                MAV_ESTIMATOR_TYPE_VISION, body_velocity=True),
}  # fmt: skip


class PoseVelocity:
    """The velocity between a pose and the latest one at least ``min_baseline_s`` before it, in
    [m/s] (NaN until there is one, and after a gap: a difference across it would be an average,
    not the velocity). Not between the last two: the truth a SITL mocap is made of arrives in
    bursts on a loaded machine (two captures 1 ms apart), and 0.2 mm of mocap noise over 1 ms is
    0.28 m/s; PX4 then refused to arm after a landing, "Preflight Fail: horizontal velocity
    unstable" for minutes (EKF2_EVV_NOISE 0.02 m/s)."""

    def __init__(self, max_gap_s: float = 0.1, min_baseline_s: float = 0.02) -> None:
        self.max_gap_s = max_gap_s
        """Longest time in [s] between two captures that are differenced."""
        self.min_baseline_s = min_baseline_s
        """Shortest time in [s] a velocity is differenced over."""
        self._poses: deque[tuple[float, Vec3]] = deque()

    def update(self, time_s: float, position_m: Vec3) -> Vec3:
        """The pose captured at ``time_s`` [s] at ``position_m`` [m]: the velocity since the
        latest pose at least ``min_baseline_s`` before (NaN without one, after a gap, and for the
        same capture again)."""
        poses = self._poses
        if poses and time_s - poses[-1][0] <= 1e-6:
            return NAN3
        if poses and time_s - poses[-1][0] > self.max_gap_s:
            poses.clear()
        poses.append((time_s, position_m))
        while len(poses) > 2 and time_s - poses[1][0] >= self.min_baseline_s:
            poses.popleft()  # poses[0] stays the latest one far enough back
        t0, p0 = poses[0]
        dt = time_s - t0
        if dt <= 0.0 or dt < self.min_baseline_s - 1e-9:
            return NAN3
        return ((position_m[0] - p0[0]) / dt, (position_m[1] - p0[1]) / dt,
                (position_m[2] - p0[2]) / dt)  # fmt: skip


def ned_to_body_frd(velocity_ned: Vec3, roll_rad: float, pitch_rad: float, yaw_rad: float) -> Vec3:
    """A NED vector in the FRD body frame of attitude (roll, pitch, yaw) [rad] in NED."""
    r = euler_to_matrix(roll_rad, pitch_rad, yaw_rad)  # body -> NED
    n, e, d = velocity_ned
    return (r[0][0] * n + r[1][0] * e + r[2][0] * d, r[0][1] * n + r[1][1] * e + r[2][1] * d,
            r[0][2] * n + r[1][2] * e + r[2][2] * d)  # fmt: skip


def encode_odometry(
    mav: Any,
    flavor: Flavor,
    usec: int,
    position_m_ned: Vec3,
    attitude_rad_ned: Vec3,
    velocity_mps_ned: Vec3,
) -> Any:
    """ODOMETRY of a mocap pose captured at ``usec`` [us] for ``flavor``'s autopilot: position
    [m], attitude (roll, pitch, yaw) [rad] and velocity [m/s] in its LOCAL_NED frame, the
    covariances unknown (each autopilot takes its noise parameters)."""
    frames = ODOMETRY_FRAMES[flavor]
    velocity = (ned_to_body_frd(velocity_mps_ned, *attitude_rad_ned) if frames.body_velocity
                else velocity_mps_ned)  # fmt: skip
    unknown = [math.nan] * 21
    x, y, z = position_m_ned
    return mav.odometry_encode(
        usec, frames.frame_id, frames.child_frame_id, x, y, z,
        euler_to_quaternion(*attitude_rad_ned), *velocity, math.nan, math.nan, math.nan,
        unknown, unknown, 0, frames.estimator_type, 0,
    )  # fmt: skip

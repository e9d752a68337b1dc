"""Motion capture as the estimator's only position source, as each autopilot configures it (pure).

A companion that forwards mocap (VISION_POSITION_ESTIMATE, ATT_POS_MOCAP, or ODOMETRY in the frames
the autopilot takes: :func:`odometry_is_pose`) sets the estimator up to fuse it; from then on the
vehicle has a position only while poses keep arriving:

- ArduCopter: ExternalNav is the position source when VISO_TYPE (read at boot) is non-zero and
  EK3_SRC1_POSXY is 6; the visual odometry is healthy while a pose came within 0.3 s
  (AP_VISUALODOM_TIMEOUT_MS), and arming is refused with "PreArm: VisOdom: not healthy"
  otherwise (seen on ArduCopter 4.7 SITL while the EKF waited for the first poses);
- PX4: EKF2 fuses external-vision position when bit 0 of EKF2_EV_CTRL is set; with
  EKF2_GPS_CTRL 0 nothing else gives a position, and EKF2 stops the vision after two of its
  200 ms sample intervals without one (EV_MAX_INTERVAL): 0.4 s (on SIH a 1.2 s gap dropped it),
  and arming is denied.

:data:`MOCAP_BOOT_PARAMS` are what such a vehicle keeps in its storage across the reboot those
read-at-boot parameters need (scripts/sitl/start.py gives the real SITL binaries the same).
"""

from __future__ import annotations

import math

from mavsim.params import Flavor, ParamTable

ARDUPILOT_EXTERNAL_NAV = 6
"""EK3_SRC1_POSXY: ExternalNav."""
PX4_EV_CTRL_HPOS = 1
"""EKF2_EV_CTRL bit 0: fuse external-vision horizontal position."""
MOCAP_TIMEOUT_S: dict[Flavor, float] = {"ardupilot": 0.3, "px4": 0.4}
"""How old in [s] the last pose may be for the position to count."""
MOCAP_BOOT_PARAMS: dict[Flavor, tuple[tuple[str, float], ...]] = {
    "ardupilot": (("VISO_TYPE", 1),),
    "px4": (("EKF2_ASP_DELAY", 0.0), ("EKF2_DELAY_MAX", 20.0)),
}
"""Read-at-boot parameters of a vehicle set up for mocap (the agent refuses one without them)."""
STALE_REFUSAL: dict[Flavor, str] = {
    "ardupilot": "PreArm: VisOdom: not healthy",
    "px4": "Arming denied: Resolve system health failures first",
}
"""The pre-arm refusal while mocap is the position source and no recent pose came (PX4 1.16's
commander words any failed health check so; SIH said it when its vision had lapsed)."""


MAV_FRAME_LOCAL_NED, MAV_FRAME_LOCAL_ENU, MAV_FRAME_BODY_FRD = 1, 4, 12
MAV_FRAME_LOCAL_FRD, MAV_FRAME_LOCAL_FLU = 20, 21
PX4_ODOMETRY_POSE_FRAMES = frozenset(
    {MAV_FRAME_LOCAL_NED, MAV_FRAME_LOCAL_ENU, MAV_FRAME_LOCAL_FRD, MAV_FRAME_LOCAL_FLU}
)
PX4_VISION_ESTIMATORS = frozenset({0, 1, 2, 3})
"""MAV_ESTIMATOR_TYPE UNKNOWN, NAIVE, VISION, VIO: what PX4 1.16 hands EKF2 as vision (MOCAP goes
to a topic EKF2 does not read; GPS, LIDAR, AUTOPILOT are refused)."""


def odometry_is_pose(
    flavor: Flavor, frame_id: int, child_frame_id: int, estimator_type: int, xyz: tuple[float, ...]
) -> bool:
    """An ODOMETRY message reaches the estimator as a mocap pose: ArduPilot takes only
    MAV_FRAME_LOCAL_FRD with the velocity in MAV_FRAME_BODY_FRD (any other pair is dropped);
    PX4 a finite position in a local frame from a vision-like estimator."""
    if flavor == "ardupilot":
        return frame_id == MAV_FRAME_LOCAL_FRD and child_frame_id == MAV_FRAME_BODY_FRD
    finite = all(math.isfinite(v) for v in xyz)
    vision = estimator_type in PX4_VISION_ESTIMATORS
    return finite and vision and frame_id in PX4_ODOMETRY_POSE_FRAMES


def fuses_mocap(flavor: Flavor, params: ParamTable, viso_type_at_boot: float) -> bool:
    """Mocap is the estimator's position source with these parameters."""
    if flavor == "px4":
        ev_position = int(params["EKF2_EV_CTRL"]) & PX4_EV_CTRL_HPOS
        return bool(ev_position) and int(params["EKF2_GPS_CTRL"]) == 0
    return viso_type_at_boot > 0 and int(params["EK3_SRC1_POSXY"]) == ARDUPILOT_EXTERNAL_NAV

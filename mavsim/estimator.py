"""ESTIMATOR_STATUS as PX4 sends it (pure but for the encoder it is handed).

PX4 fills the message from its primary EKF2 instance's ``estimator_status`` topic
(src/modules/mavlink/streams/ESTIMATOR_STATUS.hpp, v1.16): ``time_usec`` the topic's timestamp
(microseconds since boot), the innovation test ratios (velocity, horizontal and vertical
position, magnetometer, height above ground, airspeed), the 1-sigma position accuracies, and
``flags`` from EKF2's ``solution_status_flags`` (ekf_helper.cpp), the ESTIMATOR_STATUS_FLAGS of
MAVLink's common.xml. Its default stream on a normal link is 0.5 Hz (mavlink_main.cpp,
``configure_stream_local("ESTIMATOR_STATUS", 0.5f)``); a companion asks for its own rate.

The simulated estimator is exact (``mavsim/params.py``), so the ratios are 0; the accuracies are
the noise the parameters give the fused source (EKF2's converged 1-sigma is below it). The flags
follow EKF2's rules with what the simulated vehicle has: a barometer from boot, a position source
(mocap through external vision, or GNSS) after the start delay, no range finder, flow or airspeed.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pymavlink.dialects.v20 import ardupilotmega as mavlink

if TYPE_CHECKING:
    from mavsim.autopilot_core import AutopilotCore

ATTITUDE = 1
VELOCITY_HORIZ = 2
VELOCITY_VERT = 4
POS_HORIZ_REL = 8
POS_HORIZ_ABS = 16
POS_VERT_ABS = 32
CONST_POS_MODE = 128
PRED_POS_HORIZ_REL = 256
PRED_POS_HORIZ_ABS = 512
"""ESTIMATOR_STATUS_FLAGS (common.xml) that EKF2 can set here. POS_VERT_AGL (64) needs a terrain
estimate (range finder or flow), GPS_GLITCH (1024) and ACCEL_ERROR (2048) a fault: never here."""

DEFAULT_INTERVAL_S = 2.0
"""PX4's own rate on a normal link, 0.5 Hz."""
GNSS_POSITION_NOISE_M = 0.5
"""EKF2_GPS_P_NOISE's default, [m]: the accuracy of a GNSS-fed solution."""
BARO_NOISE_M = 3.5
"""EKF2_BARO_NOISE's default, [m]: the vertical accuracy when the barometer is the height."""
PX4_GPS_CTRL_LON_LAT = 1
"""Bit 0 of EKF2_GPS_CTRL: fuse GNSS longitude and latitude."""
PX4_HGT_REF_VISION = 3
"""EKF2_HGT_REF for external vision as the height reference."""


def estimator_flags(ap: AutopilotCore) -> int:
    """EKF2's ``solution_status_flags`` for the simulated vehicle now."""
    flags = ATTITUDE | VELOCITY_VERT | POS_VERT_ABS  # aligned and on the barometer from boot
    gnss = _fuses_gnss(ap)
    if ap.position_source_ready:
        flags |= VELOCITY_HORIZ | POS_HORIZ_REL | PRED_POS_HORIZ_REL  # horizontal aiding active
        if gnss or ap.ekf_origin_lla is not None:  # a global position needs an origin
            flags |= POS_HORIZ_ABS
    if gnss:
        flags |= PRED_POS_HORIZ_ABS
    # fake_pos (no position source) or vehicle_at_rest (landed, motors off)
    if not ap.position_source_ready or (ap.on_ground and not ap.armed):
        flags |= CONST_POS_MODE
    return flags


def estimator_status(mav: mavlink.MAVLink, ap: AutopilotCore) -> mavlink.MAVLink_message:
    """The message, stamped with the autopilot's time."""
    if ap.fuses_mocap:
        horizontal_m = ap.params["EKF2_EVP_NOISE"]
        vision_height = ap.params["EKF2_HGT_REF"] == PX4_HGT_REF_VISION
        vertical_m = horizontal_m if vision_height else BARO_NOISE_M
    else:
        horizontal_m, vertical_m = GNSS_POSITION_NOISE_M, BARO_NOISE_M
    return mav.estimator_status_encode(
        int(ap.now_s * 1e6), estimator_flags(ap), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
        horizontal_m, vertical_m,
    )  # fmt: skip


def _fuses_gnss(ap: AutopilotCore) -> bool:
    return not ap.fuses_mocap and int(ap.params["EKF2_GPS_CTRL"]) & PX4_GPS_CTRL_LON_LAT != 0

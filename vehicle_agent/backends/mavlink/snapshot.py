"""What the MAVLink backend reports of its vehicle each tick, in the show frame (pure).

Position, velocity and attitude are the autopilot's own estimate (LOCAL_NED and ATTITUDE turned
ENU, the body FLU); on the ground when EXTENDED_SYS_STATE says landed (before it does: when
disarmed). The pen is modelled from the simulator's true pose when the backend reads it (SITL),
otherwise from the estimate and ATTITUDE. Idle on the ground and disarmed, ``preflight`` is why
the autopilot would not arm (SYS_STATUS, and its words in STATUSTEXT), or else why the backend
would not arm it (its estimate off the mocap); while a landing ends (PX4 put in Hold) it is not
asked yet.
"""

from __future__ import annotations

import math

from vehicle_agent.backends.base import BackendMode, LinkHealth, Vec3, VehicleSnapshot
from vehicle_agent.backends.mavlink.errors import off_the_mocap_reason
from vehicle_agent.backends.mavlink.frames import attitude_ned_to_xyzw_enu, ned_to_enu
from vehicle_agent.backends.mavlink.pen import PenOverBoard
from vehicle_agent.backends.mavlink.state import MAV_LANDED_STATE_ON_GROUND, LinkState
from vehicle_agent.backends.mavlink.truth import TruthSample
from vehicles.kind import PenReading


def pen_reading(
    pen: PenOverBoard | None,
    position_m_enu: Vec3,
    attitude_ned_rad: Vec3 | None,
    truth: TruthSample | None,
) -> PenReading | None:
    """The pen of a vehicle on the simulator's ``truth`` if read, else at ``position_m_enu`` in
    [m] (the estimate in the show frame) with this ATTITUDE (``attitude_ned_rad``, [rad]); None
    without a pen or an attitude."""
    body, attitude = (position_m_enu, attitude_ned_rad) if truth is None else (
        truth.position_m_enu, truth.attitude_ned_rad)  # fmt: skip
    return None if pen is None or attitude is None else pen.read(body, attitude)


ESTIMATE_FROM_MOCAP_MAX_M = 0.10
"""Largest distance in [m] at take-off between the autopilot's position and the mocap pose
sent to it. Fused, they agree within 2-8 cm after a take-off on PX4 SIH and 3 mm at rest
(``params.PX4_HGT_REF_VISION``, ``params.PX4_MOCAP_ACC_NOISE_MPS2``); one that had not taken the
mocap was 583.85 m off."""


def off_the_mocap_m(here_m_enu: Vec3, mocap_m_enu: Vec3 | None) -> float | None:
    """How far in [m] the autopilot's position (``here_m_enu``, [m]) is from the latest mocap
    pose we sent it (``mocap_m_enu``) when more than :data:`ESTIMATE_FROM_MOCAP_MAX_M`; None
    within it, or with no pose sent."""
    if mocap_m_enu is None:
        return None
    off_m = math.dist(here_m_enu, mocap_m_enu)
    return off_m if off_m > ESTIMATE_FROM_MOCAP_MAX_M else None


def preflight_of(state: LinkState, position_m_enu: Vec3, mocap_m_enu: Vec3 | None) -> str | None:
    """Why the vehicle would not arm now: its autopilot's words (SYS_STATUS, STATUSTEXT), else its
    estimate (``position_m_enu``, [m]) off the latest mocap pose sent to it (``mocap_m_enu``);
    None when it would."""
    if state.preflight is not None:
        return state.preflight
    off_m = off_the_mocap_m(position_m_enu, mocap_m_enu)
    return None if off_m is None else off_the_mocap_reason(off_m)


def vehicle_snapshot(
    state: LinkState,
    now_s: float,
    position_m_enu: Vec3,
    truth: TruthSample | None,
    *,
    mode: BackendMode,
    fault: str | None,
    reading: PenReading | None,
    health: LinkHealth | None = None,
    mocap_m_enu: Vec3 | None = None,
) -> VehicleSnapshot:
    """The vehicle at ``now_s`` in [s] as ``state`` has it, at ``position_m_enu`` in [m] (the
    estimate in the show frame), with the simulator's ``truth`` if read and the backend's
    ``mode`` and ``fault``; ``reading``: the pen it carries, as :func:`pen_reading` read it
    (None: no pen); ``health``: the figures of the agent's preflight; ``mocap_m_enu``: the
    latest mocap pose sent to the autopilot (None: none), asked only on the ground, disarmed."""
    st = state
    said = st.landed_state
    on_ground = said == MAV_LANDED_STATE_ON_GROUND if said is not None else not st.armed
    estimated = st.attitude_ned
    estimated_attitude = None if estimated is None else attitude_ned_to_xyzw_enu(*estimated)
    return VehicleSnapshot(
        t_s=now_s,
        position_m_enu=position_m_enu,
        velocity_mps_enu=ned_to_enu(st.velocity_ned),
        armed=st.armed,
        mode=mode,
        on_ground=on_ground,
        battery_fraction=st.battery_fraction,
        battery_voltage_v=st.battery_voltage_v,
        battery_minutes_left=st.battery_minutes_left,
        fault=fault,
        pen_tip_m_enu=None if reading is None else reading.tip_m_enu,
        pen_width_m=None if reading is None else reading.width_m,
        pen_contact=None if reading is None else reading.contact,
        attitude_xyzw_enu=estimated_attitude,
        autopilot_mode=None if st.flavor is None else st.flavor.mode_name(st.custom_mode or 0),
        true_position_m_enu=None if truth is None else truth.position_m_enu,
        preflight=preflight_of(st, position_m_enu, mocap_m_enu)
        if mode == "idle" and on_ground and not st.armed
        else None,
        health=health,
    )

"""A simulator's truth off the autopilot link (SIM_STATE, HIL_STATE_QUATERNION); mocap from it."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from vehicle_agent.backends.mavlink.frames import euler_to_quaternion
from vehicle_agent.backends.mavlink.truth import TruthTracker, geodetic, truth_mocap

MAV = mavlink.MAVLink(None, srcSystem=1)
LAT0, LON0, ALT0 = -35.363261, 149.165230, 584.0
HOME = (-1.0, -1.2, 0.0)
METRES_PER_DEG = math.radians(1.0) * 6_378_137.0


def sim_state(lat: float, lon: float, alt: float, yaw: float = 0.0) -> object:
    """What ArduPilot SITL sends (its float lat/lon are coarse; the int fields are exact)."""
    message = MAV.sim_state_encode(1, 0, 0, 0, 0.01, -0.02, yaw, 0, 0, 0, 0, 0, 0,
                                   lat * 1e7, lon * 1e7, alt, 0, 0, 0, 0, 0,
                                   round(lat * 1e7), round(lon * 1e7))  # fmt: skip
    return mavlink.MAVLink(None).decode(bytearray(message.pack(MAV)))


def hil_state(lat: float, lon: float, alt: float, yaw: float = 0.0) -> object:
    """What PX4 SITL sends from its ground truth (alt in mm)."""
    q = euler_to_quaternion(0.01, -0.02, yaw)
    fix = (round(lat * 1e7), round(lon * 1e7), round(alt * 1000))
    message = MAV.hil_state_quaternion_encode(0, q, 0, 0, 0, *fix, 0, 0, 0, 0, 0, 0, 0, 0)
    return mavlink.MAVLink(None).decode(bytearray(message.pack(MAV)))


@pytest.mark.parametrize("make", [sim_state, hil_state])
def test_truth_is_placed_from_the_home_anchor(make: object) -> None:
    tracker = TruthTracker(HOME)
    assert not tracker.absorb(make(LAT0, LON0, ALT0), 0.0, resting_at_home=False)  # type: ignore[operator]
    assert tracker.anchor is None  # never anchored in flight
    assert tracker.absorb(make(LAT0, LON0, ALT0), 0.1, resting_at_home=True)  # type: ignore[operator]
    # one metre north (1e-7 deg steps: ~1.1 cm), half a metre east, 0.75 m up
    north_deg = 1.0 / METRES_PER_DEG
    east_deg = 0.5 / (METRES_PER_DEG * math.cos(math.radians(LAT0)))
    tracker.absorb(make(LAT0 + north_deg, LON0 + east_deg, ALT0 + 0.75, 0.3), 0.2,  # type: ignore[operator]
                   resting_at_home=False)  # fmt: skip
    sample = tracker.latest
    assert sample is not None
    expected = (HOME[0] + 0.5, HOME[1] + 1.0, HOME[2] + 0.75)
    assert sample.position_m_enu == pytest.approx(expected, abs=0.006)
    assert sample.attitude_ned_rad == pytest.approx((0.01, -0.02, 0.3), abs=1e-5)


def test_geodetic_ignores_other_messages() -> None:
    heartbeat = MAV.heartbeat_encode(2, 3, 0, 0, 4)
    assert geodetic(mavlink.MAVLink(None).decode(bytearray(heartbeat.pack(MAV)))) is None


def test_mocap_from_truth_has_the_shows_latency_and_noise() -> None:
    tracker = TruthTracker(HOME, history_s=2.0)
    for k in range(100):  # 1 m/s north, 100 Hz
        lat = LAT0 + (0.01 * k) / METRES_PER_DEG
        tracker.absorb(sim_state(lat, LON0, ALT0), 0.01 * k, resting_at_home=k == 0)
    source = truth_mocap(tracker, latency_s=0.05, noise_std_m=0.002, seed=3)
    poses = [source(0.99) for _ in range(400)]
    assert all(p is not None and p.time_s == pytest.approx(0.94) for p in poses)
    north = np.array([p.position_m_enu[1] for p in poses if p is not None]) - HOME[1]
    assert float(np.mean(north)) == pytest.approx(0.94, abs=0.006)  # 50 ms old, not 0.99
    assert float(np.std(north)) == pytest.approx(0.002, rel=0.2)
    assert truth_mocap(tracker, 0.0, 0.0, seed=0)(-1.0) is None  # nothing that old

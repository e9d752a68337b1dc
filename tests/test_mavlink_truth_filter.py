"""The SITL truth without its centimetre steps: SIM_STATE's 1e-7 degree and whole-centimetre
positions smoothed on its unquantized velocity."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

from vehicle_agent.backends.mavlink.truth import EARTH_RADIUS_M, TruthTracker
from vehicle_agent.backends.mavlink.truth_filter import SmoothedTruthTracker

LAT0, LON0, ALT0 = -35.363261, 149.165230, 584.0
HOME = (0.0, -1.0, 0.0)


def sim_state(
    north_m: float, east_m: float, up_m: float, v_enu: tuple[float, float, float]
) -> mav.MAVLink_sim_state_message:
    """ArduPilot SITL's SIM_STATE of a point ``north_m``/``east_m``/``up_m`` from the start, its
    position quantized as ArduPilot sends it (1e-7 degrees, whole centimetres)."""
    lat = LAT0 + math.degrees(north_m / EARTH_RADIUS_M)
    lon = LON0 + math.degrees(east_m / (EARTH_RADIUS_M * math.cos(math.radians(LAT0))))
    alt = round((ALT0 + up_m) * 100.0) / 100.0
    return mav.MAVLink_sim_state_message(
        1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, alt, 0, 0,
        v_enu[1], v_enu[0], -v_enu[2], round(lat * 1e7), round(lon * 1e7),
    )  # fmt: skip


def fly(tracker: TruthTracker) -> float:
    """A slow diagonal stroke (0.07 m/s east, 0.05 m/s north, 0.03 m/s up) sampled at 50 Hz;
    the RMS in [m] of the tracker's positions from the true ones after the first second."""
    v = (0.07, 0.05, 0.03)
    errors = []
    for k in range(400):
        t = k * 0.02
        north, east, up = v[1] * t, v[0] * t, v[2] * t
        assert tracker.absorb(sim_state(north, east, up, v), t, resting_at_home=(k == 0))
        if t >= 1.0:
            got = np.subtract(tracker.samples[-1].position_m_enu, HOME)
            errors.append(float(np.linalg.norm(got - np.array([east, north, up]))))
    return float(np.sqrt(np.mean(np.square(errors))))


def test_the_smoothing_removes_most_of_the_quantization() -> None:
    raw, smoothed = fly(TruthTracker(HOME)), fly(SmoothedTruthTracker(HOME))
    assert raw > 0.004  # about a centimetre's steps on each axis
    assert smoothed < 0.3 * raw


def test_a_jump_the_velocity_does_not_explain_is_taken_as_it_is() -> None:
    tracker = SmoothedTruthTracker(HOME)
    tracker.absorb(sim_state(0.0, 0.0, 0.0, (0.0, 0.0, 0.0)), 0.0, resting_at_home=True)
    tracker.absorb(sim_state(0.0, 0.5, 0.0, (0.0, 0.0, 0.0)), 0.02, resting_at_home=False)
    assert tracker.samples[-1].position_m_enu[0] == pytest.approx(0.5, abs=0.011)

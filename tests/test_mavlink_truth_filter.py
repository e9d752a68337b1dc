"""The SITL truth without its centimetre steps: SIM_STATE's 1e-7 degree and whole-centimetre
positions smoothed on its unquantized velocity, PX4 SIH's HIL_STATE_QUATERNION on its truncated
whole cm/s."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav

from vehicle_agent.backends.mavlink.odometry import PoseVelocity
from vehicle_agent.backends.mavlink.truth import EARTH_RADIUS_M, TruthTracker
from vehicle_agent.backends.mavlink.truth_filter import (
    CLOCK_SLACK_S,
    SimulatorClock,
    SmoothedTruthTracker,
    carry_s,
    mid_step_mps,
    own_time_s,
    simulator_time_s,
)

LAT0, LON0, ALT0 = -35.363261, 149.165230, 584.0
HOME = (0.0, -1.0, 0.0)


def lat_lon_deg(
    north_m: float, east_m: float, home_deg: tuple[float, float] = (LAT0, LON0)
) -> tuple[float, float]:
    """Latitude and longitude in [deg] of a point ``north_m``/``east_m`` [m] from ``home_deg``."""
    lat0, lon0 = home_deg
    east_radius_m = EARTH_RADIUS_M * math.cos(math.radians(lat0))
    return lat0 + math.degrees(north_m / EARTH_RADIUS_M), lon0 + math.degrees(
        east_m / east_radius_m
    )


def sim_state(
    north_m: float, east_m: float, up_m: float, v_enu: tuple[float, float, float]
) -> mav.MAVLink_sim_state_message:
    """ArduPilot SITL's SIM_STATE of a point ``north_m``/``east_m``/``up_m`` from the start, its
    position quantized as ArduPilot sends it (1e-7 degrees, whole centimetres)."""
    lat, lon = lat_lon_deg(north_m, east_m)
    alt = round((ALT0 + up_m) * 100.0) / 100.0
    return mav.MAVLink_sim_state_message(
        1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, alt, 0, 0,
        v_enu[1], v_enu[0], -v_enu[2], round(lat * 1e7), round(lon * 1e7),
    )  # fmt: skip


def hil_state_quaternion(
    north_m: float,
    east_m: float,
    up_m: float,
    v_enu: tuple[float, float, float],
    taken_s: float = 0.0,
) -> mav.MAVLink_hil_state_quaternion_message:
    """PX4 SIH's HIL_STATE_QUATERNION of the same point, as PX4 v1.16 fills it: lat/lon in 1e-7
    degrees, alt in millimetres and the velocity in cm/s, each a float stored in an integer
    (truncated towards zero). The home lies half-way along its 1e-7 degree steps, as
    ``scripts/sitl/start.py`` places each PX4 (the truncation's offset then averages out).
    ``taken_s``: the sample's own time in [s] (0: none, as PX4 as shipped sends it)."""
    lat, lon = lat_lon_deg(north_m, east_m, home_deg=(LAT0 - 0.5e-7, LON0 + 0.5e-7))
    vx, vy, vz = (math.trunc(100.0 * c) for c in (v_enu[1], v_enu[0], -v_enu[2]))
    return mav.MAVLink_hil_state_quaternion_message(
        round(taken_s * 1e6), [1.0, 0.0, 0.0, 0.0], 0.0, 0.0, 0.0,
        math.trunc(lat * 1e7), math.trunc(lon * 1e7), math.trunc((ALT0 + up_m) * 1e3),
        vx, vy, vz, 0, 0, 0, 0, 0,
    )  # fmt: skip


def fly(
    tracker: TruthTracker,
    *,
    v: tuple[float, float, float] = (0.07, 0.05, 0.03),
    wall_per_sim: float = 1.0,
    simulator_clock: bool = False,
) -> float:
    """A slow diagonal stroke (``v`` in [m/s], ENU) sampled at 50 Hz of the simulator's clock,
    which runs ``wall_per_sim`` times slower than the agent's (a loaded machine), the tracker
    told the simulator's clock when ``simulator_clock``; the RMS in [m] of the tracker's
    positions from the true ones after the first two seconds."""
    errors = []
    for k in range(500):
        t = k * 0.02
        north, east, up = v[1] * t, v[0] * t, v[2] * t
        message, arrived_s = sim_state(north, east, up, v), t * wall_per_sim
        if isinstance(tracker, SmoothedTruthTracker):
            simulator_s = simulator_time_s(round(t * 1000)) if simulator_clock else None
            assert tracker.absorb(message, arrived_s, resting_at_home=(k == 0),
                                  simulator_s=simulator_s)  # fmt: skip
        else:
            assert tracker.absorb(message, arrived_s, resting_at_home=(k == 0))
        if t >= 2.0:
            got = np.subtract(tracker.samples[-1].position_m_enu, HOME)
            errors.append(float(np.linalg.norm(got - np.array([east, north, up]))))
    return float(np.sqrt(np.mean(np.square(errors))))


def test_the_smoothing_removes_most_of_the_quantization() -> None:
    raw, smoothed = fly(TruthTracker(HOME)), fly(SmoothedTruthTracker(HOME))
    assert raw > 0.004  # about a centimetre's steps on each axis
    assert smoothed < 0.3 * raw


def test_px4s_truncated_velocity_is_read_as_the_middle_of_its_step() -> None:
    assert [mid_step_mps(n) for n in (3, -3, 0)] == pytest.approx([0.035, -0.035, 0.0])


@pytest.mark.parametrize(("radius_m", "rate_rad_s"), [(0.1, 0.6), (0.05, 1.0), (0.2, 0.5)])
def test_px4s_truth_is_smoothed_on_its_truncated_velocity(
    radius_m: float, rate_rad_s: float
) -> None:
    """A loop written at 5-10 cm/s on PX4 SIH, whose velocity comes in whole cm/s truncated:
    read as whole cm/s, the smoothed truth trailed the vehicle by 3 mm RMS (0.5 cm/s short on
    average, over the 0.4 s time constant); read as the middle of each step, about 1 mm."""
    trackers = {"raw": TruthTracker(HOME), "smoothed": SmoothedTruthTracker(HOME)}
    errors_m: dict[str, list[float]] = {name: [] for name in trackers}
    for k in range(1000):
        t = k * 0.02
        angle = rate_rad_s * t
        east, north = radius_m * math.sin(angle), radius_m * (1.0 - math.cos(angle))
        speed = radius_m * rate_rad_s
        message = hil_state_quaternion(
            north, east, 0.0, (speed * math.cos(angle), speed * math.sin(angle), 0.0)
        )
        for name, tracker in trackers.items():
            assert tracker.absorb(message, t, resting_at_home=(k == 0))
            if t >= 2.0:
                got = np.subtract(tracker.samples[-1].position_m_enu, HOME)
                errors_m[name].append(float(np.linalg.norm(got - (east, north, 0.0))))
    raw, smoothed = (float(np.sqrt(np.mean(np.square(errors_m[n])))) for n in trackers)
    assert raw > 0.0035  # about a centimetre's steps on each axis
    assert smoothed < 0.0016  # read as whole cm/s: 2.9-3.1 mm


def test_the_velocity_moves_the_position_by_the_simulators_seconds() -> None:
    """A loaded SITL runs slower than the agent's clock: integrated over the agent's seconds,
    its velocity carried the smoothed truth ahead of the vehicle along a writing stroke."""
    stroke = (0.2, 0.0, 0.0)
    by_arrival = fly(SmoothedTruthTracker(HOME), v=stroke, wall_per_sim=1.5)
    by_simulator = fly(SmoothedTruthTracker(HOME), v=stroke, wall_per_sim=1.5,
                       simulator_clock=True)  # fmt: skip
    assert by_arrival > 0.01  # half the velocity again, over the time constant
    assert by_simulator < 0.002
    unloaded = fly(SmoothedTruthTracker(HOME), v=stroke, simulator_clock=True)
    assert by_simulator == pytest.approx(unloaded, abs=5e-4)


def test_a_clock_that_stands_still_or_runs_ahead_leaves_the_arrivals_time() -> None:
    """PX4 leaves HIL_STATE_QUATERNION's time_usec 0 and an ATTITUDE can be lost: a stopped
    clock must not freeze the truth (fed back as the mocap, a frozen truth made a PX4 climb into
    its geofence), nor a jump throw it ahead."""
    assert simulator_time_s(5_250) == pytest.approx(5.25)
    assert simulator_time_s(0) is None  # no ATTITUDE yet
    clock = SimulatorClock(seen_s=1.0, at_s=1.0)
    assert carry_s(clock, 1.015, 0.02)[0] == pytest.approx(0.015)  # slower than the agent
    assert carry_s(clock, None, 0.02)[0] == carry_s(clock, 1.0, 0.02)[0] == 0.02
    assert carry_s(clock, 1.5, 0.02)[0] == pytest.approx(0.02 + CLOCK_SLACK_S)
    tracker = SmoothedTruthTracker(HOME)
    for k in range(100):  # climbing at 0.5 m/s on a clock that never moves
        up, v = 0.005 * k, (0.0, 0.0, 0.5)
        tracker.absorb(sim_state(0.0, 0.0, up, v), 0.01 * k, resting_at_home=(k == 0),
                       simulator_s=7.0)  # fmt: skip
    assert tracker.samples[-1].position_m_enu[2] == pytest.approx(0.495, abs=0.006)


@pytest.mark.parametrize("attitudes_per_truth", [1.0, 0.5, 0.8])
def test_a_clock_that_skips_a_sample_is_not_counted_twice(attitudes_per_truth: float) -> None:
    """The ATTITUDE standing for the simulator's clock does not always come between two truth
    samples: the time carried over on the arrivals while it stood still is paid back by its next
    step, so a steady transit is neither ahead nor behind (counted twice, PX4 SIH's smoothed
    truth ran 2-3 cm ahead and snapped back)."""
    tracker = SmoothedTruthTracker(HOME)
    speed_mps, period_s, errors_m = 0.5, 0.02, []
    for k in range(200):  # east at 0.5 m/s, a truth sample each 20 ms
        t = k * period_s
        clock_ms = 1000 + round(math.floor(k * attitudes_per_truth) / attitudes_per_truth * 20)
        tracker.absorb(sim_state(0.0, speed_mps * t, 0.0, (speed_mps, 0.0, 0.0)), t,
                       resting_at_home=(k == 0), simulator_s=clock_ms * 1e-3)  # fmt: skip
        if k > 20:
            errors_m.append(tracker.samples[-1].position_m_enu[0] - HOME[0] - speed_mps * t)
    # counted twice: 12-14 mm ahead on average, up to 31 mm
    assert abs(float(np.mean(errors_m))) < 0.003
    assert max(abs(e) for e in errors_m) < 0.008


def test_a_jump_the_velocity_does_not_explain_is_taken_as_it_is() -> None:
    tracker = SmoothedTruthTracker(HOME)
    tracker.absorb(sim_state(0.0, 0.0, 0.0, (0.0, 0.0, 0.0)), 0.0, resting_at_home=True)
    tracker.absorb(sim_state(0.0, 0.5, 0.0, (0.0, 0.0, 0.0)), 0.02, resting_at_home=False)
    assert tracker.samples[-1].position_m_enu[0] == pytest.approx(0.5, abs=0.011)


@pytest.mark.parametrize("stamped", [True, False])
def test_a_stamped_truth_keeps_the_simulators_spacing_through_a_jittery_link(
    stamped: bool,
) -> None:
    """PX4 SIH's truth every 20 ms of its clock, arriving 1-12 ms late at random (a loaded
    machine; the first 15 read at once, a backlog), smoothed on the simulator's seconds and read
    as the mocap's velocity is (differenced over the samples' times). Stamped on arrival, the
    velocity along a 9.3 cm/s stroke wobbles by 14 mm/s; stamped with the truth's own time (PX4
    built with scripts/sitl/source_edits.py) by what its whole-cm/s steps leave, 6 mm/s, and on
    the right mean."""
    rng = np.random.default_rng(7)
    tracker, velocity, east_mps = SmoothedTruthTracker(HOME), PoseVelocity(), []
    for k in range(600):
        t = 100.0 + k * 0.02  # PX4's clock since boot
        message = hil_state_quaternion(0.0, 0.093 * k * 0.02, 0.0, (0.093, 0.0, 0.0),
                                       t if stamped else 0.0)  # fmt: skip
        arrived_s = 5.0 + k * 0.02 + float(rng.uniform(0.001, 0.012))
        if k < 15:  # a backlog, read at once as the agent starts
            arrived_s = 5.3 + 1e-4 * k
        assert tracker.absorb(message, arrived_s, resting_at_home=(k == 0), simulator_s=t)
        sample = tracker.samples[-1]
        if k > 15:  # never after it arrived, and the least delay soon found
            assert arrived_s - 0.012 < sample.time_s <= arrived_s + (1e-9 if k > 60 else 0.3)
        v = velocity.update(sample.time_s, sample.position_m_enu)
        if k > 100 and not math.isnan(v[0]):
            east_mps.append(v[0])
    wobble_mps = float(np.std(east_mps))
    mean_mps = float(np.mean(east_mps))
    if stamped:
        assert own_time_s(message) == pytest.approx(t)
        assert mean_mps == pytest.approx(0.093, abs=0.0015)
        assert wobble_mps < 0.008  # the whole-cm/s steps' share
    else:  # 14 mm/s, and 4 mm/s slow: the 20 ms baseline picks the pairs that came further apart
        assert own_time_s(message) is None
        assert wobble_mps > 0.012


def exact_truth(
    north_m: float, east_m: float, up_m: float, v_enu: tuple[float, float, float], taken_s: float
) -> mav.MAVLink_local_position_ned_cov_message:
    """What a PX4 built with scripts/sitl/source_edits.py sends right after each
    HIL_STATE_QUATERNION: the same truth's local NED position and velocity as floats, from SIH's
    own origin (here 3 m north of the home), stamped the same."""
    return mav.MAVLink_local_position_ned_cov_message(
        round(taken_s * 1e6), 0, north_m - 3.0, east_m, -up_m, v_enu[1], v_enu[0], -v_enu[2],
        0.0, 0.0, 0.0, [math.nan] + [0.0] * 44,
    )  # fmt: skip


@pytest.mark.parametrize("floats", [True, False])
def test_px4s_truth_to_the_float_takes_the_place_of_its_steps(floats: bool) -> None:
    """A 9.3 cm/s stroke with a turn, PX4 SIH's truth every 20 ms arriving 1-12 ms late; the
    mocap's velocity differenced over the samples' times, as it is sent. With the floats beside
    HIL_STATE_QUATERNION the positions are the truth's own from the anchor at rest and the
    velocity is the stroke's; from the 1e-7 degree and whole-cm/s steps alone they are a
    millimetre off and the velocity wobbles by several mm/s."""
    rng = np.random.default_rng(11)
    tracker, velocity = SmoothedTruthTracker(HOME), PoseVelocity()
    errors_m, velocity_errors_mps = [], []
    for k in range(600):
        t = 100.0 + k * 0.02
        s = k * 0.02
        east, north = 0.093 * s, 0.05 * math.sin(0.8 * s)
        v = (0.093, 0.04 * math.cos(0.8 * s), 0.0)
        arrived_s = 5.0 + s + float(rng.uniform(0.001, 0.012))
        placed = tracker.absorb(hil_state_quaternion(north, east, 0.0, v, t), arrived_s,
                                resting_at_home=(k == 0), simulator_s=t)  # fmt: skip
        if floats:
            assert placed == (k == 0)  # the floats of the same truth follow
            assert tracker.absorb(exact_truth(north, east, 0.0, v, t), arrived_s + 1e-4,
                                  resting_at_home=(k == 0))  # fmt: skip
        sample = tracker.samples[-1]
        if k > 100:
            truth = (HOME[0] + east, HOME[1] + north, HOME[2])
            errors_m.append(float(np.linalg.norm(np.subtract(sample.position_m_enu, truth))))
            got = velocity.update(sample.time_s, sample.position_m_enu)
            if not math.isnan(got[0]):
                velocity_errors_mps.append(float(np.hypot(got[0] - v[0], got[1] - v[1])))
        else:
            velocity.update(sample.time_s, sample.position_m_enu)
    position_rms_m = float(np.sqrt(np.mean(np.square(errors_m))))
    velocity_rms_mps = float(np.sqrt(np.mean(np.square(velocity_errors_mps))))
    if floats:
        assert tracker.exact_anchor_m_ned == pytest.approx((-3.0, 0.0, 0.0))
        assert position_rms_m < 1e-5
        assert velocity_rms_mps < 0.0008  # the stroke's turn over a 20 ms difference
    else:
        assert position_rms_m > 0.0005
        assert velocity_rms_mps > 0.002


def test_px4s_truth_to_the_float_is_never_anchored_in_flight() -> None:
    """An agent started while the vehicle flies places no truth from the floats either, and the
    floats alone (no attitude yet) place nothing."""
    tracker = SmoothedTruthTracker(HOME)
    assert not tracker.absorb(exact_truth(0.0, 0.0, 0.0, (0, 0, 0), 1.0), 0.0,
                              resting_at_home=True)  # fmt: skip
    tracker.absorb(hil_state_quaternion(0.0, 0.0, 1.0, (0, 0, 0), 1.0), 0.0, resting_at_home=False)
    assert not tracker.absorb(exact_truth(0.0, 0.0, 1.0, (0, 0, 0), 1.0), 0.0,
                              resting_at_home=False)  # fmt: skip
    assert tracker.exact_anchor_m_ned is None and not tracker.samples

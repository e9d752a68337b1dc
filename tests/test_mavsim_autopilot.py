"""The simulated ArduCopter without sockets: modes, arming, take-off, guided tracking, failsafes."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mavsim.autopilot import Autopilot, Result
from mavsim.config import PositionGains, VehicleConfig
from mavsim.control import Target, thrust_to_attitude
from mavsim.errors import MavsimError
from mavsim.modes import CopterMode
from vehicle_agent.motion import plan_move
from vehicles.quadrotor_brush.dynamics import body_z_axis

HOME = (1.0, -1.2, 0.0)


class Sim:
    """An autopilot and its clock."""

    def __init__(self, **overrides: object) -> None:
        config = VehicleConfig(vehicle_id="v", system_id=1, port=0, home_m_enu=HOME,
                               **overrides)  # type: ignore[arg-type]  # fmt: skip
        self.ap = Autopilot(config)
        self.t = 0.0

    def run(self, seconds: float) -> None:
        for _ in range(round(seconds / self.ap.airframe.dt_s)):
            self.t += self.ap.airframe.dt_s
            self.ap.step(self.t)

    def airborne(self, altitude_m: float = 0.8) -> None:
        self.run(self.ap.config.position_source_delay_s + 0.1)
        assert self.ap.set_mode(CopterMode.GUIDED) == Result.ACCEPTED
        assert self.ap.arm() == Result.ACCEPTED
        assert self.ap.takeoff(altitude_m) == Result.ACCEPTED
        self.run(altitude_m / self.ap.config.takeoff_speed_mps + 2.0)

    def texts(self) -> list[str]:
        texts = [text for _, text in self.ap.texts]
        self.ap.texts.clear()
        return texts


def test_arming_is_refused_until_the_position_source_is_ready() -> None:
    sim = Sim(position_source_delay_s=2.0)
    assert sim.ap.set_mode(CopterMode.GUIDED) == Result.ACCEPTED  # disarmed: any mode
    assert sim.ap.arm() == Result.FAILED
    assert sim.texts() == ["PreArm: Need Position Estimate"]
    sim.run(2.05)
    assert sim.ap.arm() == Result.ACCEPTED
    assert sim.ap.armed


def test_a_forced_refusal_names_its_reason() -> None:
    sim = Sim(position_source_delay_s=0.0, arm_refusal="Compass not calibrated")
    sim.run(0.1)
    assert sim.ap.arm() == Result.FAILED
    assert sim.texts() == ["PreArm: Compass not calibrated"]
    assert not sim.ap.armed


def test_takeoff_climbs_to_param7_above_home_and_holds() -> None:
    sim = Sim(position_source_delay_s=0.0)
    assert sim.ap.takeoff(1.0) == Result.FAILED  # not GUIDED, not armed
    sim.airborne(1.0)
    x, y, z = sim.ap.airframe.position_m_enu
    assert z == pytest.approx(HOME[2] + 1.0, abs=0.02)
    assert math.hypot(x - HOME[0], y - HOME[1]) < 0.01
    assert sim.ap.submode == "track"
    sim.run(5.0)  # holds without setpoints: no GUID_TIMEOUT before the first setpoint
    assert sim.ap.airframe.position_m_enu[2] == pytest.approx(HOME[2] + 1.0, abs=0.01)


def test_guided_follows_pva_setpoints_closely() -> None:
    sim = Sim(position_source_delay_s=0.0)
    sim.airborne()
    start = sim.ap.airframe.position_m_enu
    move = plan_move(start, (start[0] + 0.6, start[1] + 0.4, start[2]), sim.t,
                     v_max_mps=0.6, a_max_mps2=0.8)  # fmt: skip
    worst = 0.0
    steps = 0
    while not move.done(sim.t - 0.5):
        if steps % 2 == 0:  # 50 Hz setpoints into the 100 Hz autopilot loop
            sp = move.setpoint(sim.t)
            sim.ap.position_target(
                Target(sp.position_m_enu, sp.velocity_mps_enu, sp.acceleration_mps2_enu), 0
            )
        sim.run(sim.ap.airframe.dt_s)
        steps += 1
        worst = max(
            worst, math.dist(sim.ap.airframe.position_m_enu, move.setpoint(sim.t).position_m_enu)
        )
    assert worst < 0.01
    assert math.dist(sim.ap.airframe.position_m_enu, move.end_m_enu) < 0.005


def test_guided_timeout_stops_a_velocity_target_silently_as_arducopter_does() -> None:
    sim = Sim(position_source_delay_s=0.0, guided_timeout_s=1.0)
    sim.airborne()
    here = sim.ap.airframe.position_m_enu
    # one setpoint that asks for 0.3 m/s forever: the target runs on until the timeout
    sim.ap.position_target(Target(here, (0.3, 0.0, 0.0)), 0)
    sim.texts()
    sim.run(0.9)
    moving = sim.ap.target.velocity_mps_enu
    sim.run(0.3)
    assert moving == (0.3, 0.0, 0.0) and sim.ap.target.velocity_mps_enu == (0.0, 0.0, 0.0)
    assert sim.ap.submode == "track" and sim.texts() == []  # ArduCopter says nothing
    sim.run(3.0)
    stopped_at = sim.ap.airframe.position_m_enu
    assert 0.25 < stopped_at[0] - here[0] < 0.5  # about 1 s at 0.3 m/s, then braked
    sim.run(1.0)
    assert math.dist(sim.ap.airframe.position_m_enu, stopped_at) < 0.01
    assert np.linalg.norm(sim.ap.airframe.velocity_mps_enu) < 0.01
    assert sim.ap.position_target(Target(here), 0)  # setpoints resume following


def test_a_position_only_target_never_times_out() -> None:
    sim = Sim(position_source_delay_s=0.0, guided_timeout_s=0.5)
    sim.airborne()
    here = sim.ap.airframe.position_m_enu
    goal = (here[0] + 0.5, here[1], here[2])
    assert sim.ap.position_target(Target(goal), 0)
    sim.run(5.0)
    assert math.dist(sim.ap.airframe.position_m_enu, goal) < 0.01


def test_setpoints_are_ignored_outside_guided_and_a_pilot_mode_holds() -> None:
    sim = Sim(position_source_delay_s=0.0)
    sim.airborne()
    here = sim.ap.airframe.position_m_enu
    assert sim.ap.set_mode(CopterMode.LOITER) == Result.ACCEPTED
    assert not sim.ap.position_target(Target((here[0] + 1.0, here[1], here[2])), 0)
    sim.run(2.0)
    assert math.dist(sim.ap.airframe.position_m_enu, here) < 0.02


def test_land_descends_touches_down_and_disarms() -> None:
    sim = Sim(position_source_delay_s=0.0)
    sim.airborne(0.6)
    assert sim.ap.land() == Result.ACCEPTED
    sim.run(0.6 / sim.ap.config.land_speed_mps + 2.5)
    assert sim.ap.on_ground and not sim.ap.armed
    assert sim.ap.airframe.position_m_enu[2] == pytest.approx(HOME[2])
    assert sim.ap.landed_state == 1


def test_disarm_in_flight_needs_force() -> None:
    sim = Sim(position_source_delay_s=0.0)
    sim.airborne(0.6)
    assert sim.ap.disarm() == Result.FAILED
    assert sim.ap.armed
    assert sim.ap.disarm(force=True) == Result.ACCEPTED
    sim.run(1.0)
    assert sim.ap.on_ground


def test_armed_on_the_ground_without_takeoff_disarms_itself() -> None:
    sim = Sim(position_source_delay_s=0.0, disarm_delay_s=1.0)
    sim.run(0.1)
    sim.ap.set_mode(CopterMode.GUIDED)
    assert sim.ap.arm() == Result.ACCEPTED
    sim.run(1.2)
    assert not sim.ap.armed


@settings(max_examples=60, deadline=None)
@given(
    ax=st.floats(-3.0, 3.0), ay=st.floats(-3.0, 3.0), az=st.floats(-3.0, 3.0),
    yaw=st.floats(-math.pi, math.pi),
)  # fmt: skip
def test_thrust_vector_of_the_attitude_command_is_the_commanded_one(
    ax: float, ay: float, az: float, yaw: float
) -> None:
    """Within the tilt limit, body z * thrust reproduces a_cmd + g e_z (sim's own body axis)."""
    g = 9.81
    command = thrust_to_attitude((ax, ay, az), yaw, g, math.radians(45.0), 100.0)
    n = body_z_axis(np.array([[command.roll_rad, command.pitch_rad, command.yaw_rad]]))[0]
    np.testing.assert_allclose(n * command.thrust_mps2, [ax, ay, az + g], atol=1e-9)


def test_config_rejects_what_cannot_fly() -> None:
    with pytest.raises(MavsimError, match="thrust_max_n"):
        VehicleConfig(vehicle_id="v", system_id=1, port=0, mass_kg=2.0, thrust_max_n=19.0)
    with pytest.raises(MavsimError, match="system_id"):
        VehicleConfig(vehicle_id="v", system_id=0, port=0)


@pytest.mark.parametrize("eps", [1.0, 0.3])
def test_position_gains_place_the_papers_poles(eps: float) -> None:
    """PID + feed-forward on a double integrator: the error poles (roots of
    s^3 + kd s^2 + kp s + ki) must be those of (s + k_i)(s^2 + 2 zeta w_n s + w_n^2) / eps."""
    gains = PositionGains.from_poles(eps)
    for (kp, kd, ki), (wn, zeta, k) in (
        ((gains.kp_xy, gains.kd_xy, gains.ki_xy), (1.772, 0.5, 0.2)),
        ((gains.kp_z, gains.kd_z, gains.ki_z), (2.089, 0.66, 0.23)),
    ):
        designed = np.roots(np.polymul([1.0, k], [1.0, 2 * zeta * wn, wn * wn])) / eps
        closed = np.roots([1.0, kd, kp, ki])
        np.testing.assert_allclose(np.sort_complex(closed), np.sort_complex(designed), rtol=1e-9)
    assert PositionGains() == PositionGains.from_poles(0.3)

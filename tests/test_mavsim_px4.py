"""The simulated PX4 without sockets: OFFBOARD's proof of life and what flies when it is lost
(PX4 v1.16's failsafe state machine, COM_OBL_RC_ACT), and the mode shown after a failsafe."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mavsim.autopilot_core import Result
from mavsim.config import VehicleConfig
from mavsim.control import Target
from mavsim.modes import CopterMode
from mavsim.px4 import Px4Autopilot

HOME = (0.5, 0.2, 0.0)


class Sim:
    """A PX4 autopilot, its clock and an OFFBOARD position stream (``hold``, None: silent)."""

    def __init__(
        self, boot_home_offset_m: tuple[float, float, float] = (0.0, 0.0, 0.0), **params: float
    ) -> None:
        config = VehicleConfig(vehicle_id="v", system_id=1, port=0, home_m_enu=HOME,
                               autopilot="px4", position_source_delay_s=0.0,
                               boot_home_offset_m=boot_home_offset_m,
                               params=tuple(params.items()))  # fmt: skip
        self.ap = Px4Autopilot(config)
        self.t = 0.0
        self.hold: tuple[float, float, float] | None = HOME

    def mode(self) -> CopterMode:
        """The mode the heartbeat shows now."""
        return self.ap.mode

    def run(self, seconds: float) -> None:
        for step in range(round(seconds / self.ap.airframe.dt_s)):
            self.t += self.ap.airframe.dt_s
            if self.hold is not None and step % 5 == 0:  # 20 Hz stream
                self.ap.position_target(Target(self.hold), 0)
            self.ap.step(self.t)

    def airborne(self, height_m: float = 1.0) -> None:
        self.run(0.5)
        assert self.ap.set_mode(CopterMode.GUIDED) == Result.ACCEPTED
        assert self.ap.arm() == Result.ACCEPTED
        self.hold = (HOME[0], HOME[1], HOME[2] + height_m)
        self.run(6.0)
        self.hold = (HOME[0] + 1.0, HOME[1], HOME[2] + height_m)  # away from home (RTL)
        self.run(8.0)
        assert math.dist(self.ap.airframe.position_m_enu, self.hold) < 0.05


def test_offboard_needs_a_live_stream_to_be_chosen_and_to_arm() -> None:
    sim = Sim()
    sim.hold = None
    sim.run(0.5)
    assert sim.ap.set_mode(CopterMode.GUIDED) == Result.FAILED
    sim.hold = HOME
    sim.run(0.3)
    assert sim.ap.set_mode(CopterMode.GUIDED) == Result.ACCEPTED
    assert sim.ap.arm() == Result.ACCEPTED


def test_a_lost_stream_shows_position_mode_stops_and_a_stream_back_resumes_offboard() -> None:
    """COM_OBL_RC_ACT 0 (default): POSCTL is shown (even without RC, as v1.16 does), the user's
    choice stays OFFBOARD; the vehicle stops where it is; setpoints again: OFFBOARD again."""
    sim = Sim()
    sim.airborne()
    sim.hold = None
    sim.run(0.9)
    assert sim.mode() == CopterMode.GUIDED  # COM_OF_LOSS_T is 1 s
    sim.run(0.3)
    assert sim.mode() == CopterMode.BRAKE and sim.ap.chosen_mode == CopterMode.GUIDED
    assert ("Failsafe activated: switching to Position") in [text for _, text in sim.ap.texts]
    here = sim.ap.airframe.position_m_enu
    sim.run(3.0)  # no sticks: zero velocity held (a perfect estimate does not drift)
    assert sim.ap.armed and math.dist(sim.ap.airframe.position_m_enu, here) < 0.05
    assert np.linalg.norm(sim.ap.airframe.velocity_mps_enu) < 0.02
    sim.hold = (HOME[0] + 0.5, HOME[1], HOME[2] + 1.0)
    sim.run(0.1)
    assert sim.mode() == CopterMode.GUIDED
    sim.run(6.0)
    assert math.dist(sim.ap.airframe.position_m_enu, sim.hold) < 0.1


@pytest.mark.parametrize(
    ("action", "shown"),
    [(1, CopterMode.ALT_HOLD), (3, CopterMode.RTL), (4, CopterMode.LAND), (5, CopterMode.LOITER)],
)
def test_com_obl_rc_act_chooses_what_flies_when_the_stream_is_lost(
    action: int, shown: CopterMode
) -> None:
    sim = Sim(COM_OBL_RC_ACT=action)
    sim.airborne()
    sim.hold = None
    sim.run(1.2)
    assert sim.mode() == shown and sim.ap.chosen_mode == CopterMode.GUIDED


def test_a_failsafe_landing_ends_disarmed_with_offboard_shown() -> None:
    """PX4 SITL: after a failsafe LAND the heartbeat that says disarmed says OFFBOARD (the
    user's choice the failsafe replaced)."""
    sim = Sim(COM_OBL_RC_ACT=4)
    sim.airborne(0.6)
    sim.hold = None
    sim.run(1.2)
    assert sim.mode() == CopterMode.LAND
    for _ in range(12):
        sim.run(1.0)
        if not sim.ap.armed:
            break
    assert not sim.ap.armed and sim.ap.on_ground
    assert sim.mode() == CopterMode.GUIDED


def test_the_prearm_bit_is_for_the_mode_it_is_in() -> None:
    """PX4 v1.16 (SYS_STATUS.hpp): the bit is ``can_arm`` of the current mode, so in OFFBOARD
    on the ground it is clear while no setpoints stream, and set in Hold, checks passing."""
    sim = Sim()
    sim.run(0.5)
    assert sim.ap.set_mode(CopterMode.GUIDED) == Result.ACCEPTED and sim.ap.prearm_bit
    sim.hold = None
    sim.run(1.2)
    assert sim.mode() == CopterMode.GUIDED and not sim.ap.prearm_bit
    assert sim.ap.prearm_failure() is None  # the checks themselves pass
    assert sim.ap.set_mode(CopterMode.LOITER) == Result.ACCEPTED and sim.ap.prearm_bit


@pytest.mark.parametrize("action", [5, 0])
def test_a_home_beyond_the_geofence_refuses_arming_until_set_where_the_vehicle_stands(
    action: int,
) -> None:
    """PX4 SIH's boot home lies 4 m from where EKF2 puts it on the mocap's origin (issue 31):
    with a fence action, beyond GF_MAX_HOR_DIST, its geofence check fails on the ground too."""
    sim = Sim(boot_home_offset_m=(2.4, -3.2, 0.0), GF_MAX_HOR_DIST=3.5, GF_ACTION=action)
    sim.run(0.5)
    assert sim.ap.set_mode(CopterMode.GUIDED) == Result.ACCEPTED
    if action:
        assert sim.ap.prearm_failure() == "Geofence: exceeding maximum distance to Home"
        assert not sim.ap.prearm_bit and sim.ap.arm() == Result.FAILED
        assert sim.ap.set_home_here() == Result.ACCEPTED
    assert sim.ap.prearm_failure() is None and sim.ap.arm() == Result.ACCEPTED


def test_set_home_here_waits_for_a_position() -> None:
    """PX4's Commander: TEMPORARILY_REJECTED while it has no position to put the home at."""
    config = VehicleConfig(vehicle_id="v", system_id=1, port=0, home_m_enu=HOME, autopilot="px4",
                           position_source_delay_s=5.0)  # fmt: skip
    assert Px4Autopilot(config).set_home_here() == Result.TEMPORARILY_REJECTED


def test_terminate_and_disarm_actions_stop_the_motors() -> None:
    for action in (6, 7):
        sim = Sim(COM_OBL_RC_ACT=action)
        sim.airborne(0.5)
        sim.hold = None
        sim.run(1.2)
        assert not sim.ap.armed


def test_a_commanded_mode_ends_the_failsafe() -> None:
    sim = Sim()
    sim.airborne()
    sim.hold = None
    sim.run(1.2)
    assert sim.ap.set_mode(CopterMode.LAND) == Result.ACCEPTED
    assert sim.ap.failsafe_mode is None and sim.ap.chosen_mode == CopterMode.LAND
    sim.hold = HOME
    sim.run(0.5)
    assert sim.mode() == CopterMode.LAND  # a stream back does not take it over again


def test_stiffer_mpc_gains_set_in_flight_make_a_faster_step() -> None:
    """PX4 flies MPC_XY_P, MPC_XY_VEL_P_ACC and MPC_XY_VEL_I_ACC as they are set now (a companion
    sets them at connect): twice the defaults reach half a 0.5 m step sooner."""
    t50 = []
    for gains in ({}, {"MPC_XY_P": 1.8, "MPC_XY_VEL_P_ACC": 3.6, "MPC_XY_VEL_I_ACC": 1.6}):
        sim = Sim()
        sim.airborne()
        for name, value in gains.items():
            sim.ap.params.set(name, value)
        start = sim.ap.airframe.position_m_enu[0]
        sim.hold = (start + 0.5, HOME[1], HOME[2] + 1.0)
        t0 = sim.t
        while sim.ap.airframe.position_m_enu[0] - start < 0.25 and sim.t - t0 < 5.0:
            sim.run(0.01)
        t50.append(sim.t - t0)
    assert t50[1] < 0.8 * t50[0], t50

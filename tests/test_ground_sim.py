"""The ground writer in MuJoCo: rollers give omnidirectional motion on the flat with traction only
along each wheel's drive direction; free joint 1 swings and a sliding roller loses friction; the
proposed wheel control climbs a step of about the wheel radius (the paper's 0.1 m is beyond the
model: benchmarks/bench_ground.py)."""

from __future__ import annotations

import numpy as np
import pytest

from vehicles.omni_wheel.climb import STEP_EDGE_X_M, climb
from vehicles.omni_wheel.geometry import OmniGeometry
from vehicles.omni_wheel.sim import OmniWorld
from vehicles.omni_wheel.terrain import Terrain
from vehicles.omni_wheel.wheel_control import BodyConfiguration, proposed_references

GEO = OmniGeometry()
RUBBER = OmniGeometry(friction_static=1.0, friction_dynamic=0.9)


def _drive(refs: np.ndarray, seconds: float) -> np.ndarray:
    world = OmniWorld(GEO, Terrain(), ((0.0, 0.0, 0.0, 0.0),), seed=3)
    start = world.truth(0).base_m_enu
    while world.t_s < seconds:
        world.step(refs[None, :])
    return world.truth(0).base_m_enu - start


def test_sideways_wheel_alone_moves_the_vehicle_sideways() -> None:
    # only the front-centre wheel drives (along y); the six x wheels hold still on their motors:
    # their rollers must let the body slide sideways
    refs = proposed_references(np.array([0.0, 0.1, 0.0]), BodyConfiguration(), GEO).rate_radps
    assert np.count_nonzero(np.abs(refs) > 1e-9) == 1
    moved = _drive(refs, 2.0)
    assert moved[1] > 0.12  # 0.2 m commanded; the one wheel slips a little
    assert abs(moved[0]) < 0.02


def test_x_wheels_drive_straight_ahead() -> None:
    refs = proposed_references(np.array([0.2, 0.0, 0.0]), BodyConfiguration(), GEO).rate_radps
    moved = _drive(refs, 2.0)
    assert moved[0] == pytest.approx(0.4, abs=0.04)
    assert abs(moved[1]) < 0.02


def test_joint_1_is_free_over_its_range() -> None:
    # the MJCF's angles are radians: the range of +-0.9 rad once read as degrees locked the joint
    world = OmniWorld(GEO, Terrain(), ((0.0, 0.0, 0.0, 0.0),))
    pitch = world.model.joint("v0_joint1_pitch")
    np.testing.assert_allclose(pitch.range, [-0.9, 0.9])


@pytest.mark.slow
def test_proposed_method_climbs_a_step_of_the_wheel_radius() -> None:
    # 60 mm: the highest the model climbs is about the wheel radius (66 mm) with either method
    result = climb("proposed", 0.06, geometry=RUBBER)
    assert result.climbed
    assert result.duration_s < 8.0
    # the front part swings on free joint 1 as the front wheels climb (nose up: negative pitch)
    assert result.log["joint_pitch_rad"].min() < -0.25
    # the references follow the body configuration: while the front part swings up, eq. 15
    # slows the middle wheels well below V0 / r (the standard method never changes them)
    middle = result.log["reference_radps"][:, 3]
    assert middle.min() < 0.6 * GEO.running_speed_mps / GEO.wheel_radius_m
    assert np.all(np.isfinite(result.slip_per_wheel[[0, 2, 3, 4, 5, 6]]))
    assert np.isnan(result.slip_per_wheel[1])  # the sideways wheel does not count


def test_a_sliding_roller_grips_with_the_dynamic_friction() -> None:
    # the front-left wheel spins while the others hold the body still: its rollers slide
    world = OmniWorld(RUBBER, Terrain(), ((0.0, 0.0, 0.0, 0.0),), seed=1)
    hubs = world.vehicles[0].hubs
    carrier = world.model.body_parentid[world.model.geom_bodyid]  # rollers hang on their hub
    refs = np.zeros(7)
    refs[0] = 6.0
    spinning_slid = held_slid = 0
    for _ in range(50):
        world.step(refs[None, :])
        friction = world.model.geom_friction[:, 0]
        dynamic = np.isclose(friction, RUBBER.friction_dynamic)
        spinning_slid += np.any(dynamic[carrier == hubs[0]])
        held_slid += np.any(dynamic[np.isin(carrier, hubs[1:])])
    assert spinning_slid > 10  # it skips over its rollers: in contact a part of the time
    assert held_slid < spinning_slid / 2  # the held wheels barely slide


@pytest.mark.slow
def test_table_1_friction_cannot_climb_a_50_mm_step() -> None:
    # with the rollers' 0.3 of Table 1 the front wheels go up (the front part swings on joint 1)
    # but the traction of the others cannot lift the middle wheels: the run ends with the middle
    # axle stuck in front of the step edge
    result = climb("proposed", 0.05, time_limit_s=6.0)
    assert not result.climbed
    assert result.log["base_m_enu"][-1, 0] < STEP_EDGE_X_M

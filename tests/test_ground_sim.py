"""The ground writer in MuJoCo: rollers give omnidirectional motion on the flat with traction only
along each wheel's drive direction; free joint 1 swings and a sliding roller loses friction; the
frames collide with the terrain; the proposed wheel control climbs a step of about the wheel
radius (the paper's 0.1 m only with the rear mass centre read forward: benchmarks/bench_ground.py);
slip is signed by the way a wheel rolls."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from vehicles.omni_wheel.climb import STEP_EDGE_X_M, climb, wheel_ratios
from vehicles.omni_wheel.floor_plan import RUBBER_ROLLERS as RUBBER
from vehicles.omni_wheel.geometry import OmniGeometry
from vehicles.omni_wheel.sim import OmniWorld, TrueState
from vehicles.omni_wheel.terrain import Step, Terrain
from vehicles.omni_wheel.wheel_control import BodyConfiguration, proposed_references

GEO = OmniGeometry()


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
        spinning_slid += int(np.any(dynamic[carrier == hubs[0]]))
        held_slid += int(np.any(dynamic[np.isin(carrier, hubs[1:])]))
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


def _rolling(velocity_mps: np.ndarray, spin_radps: float) -> TrueState:
    """One vehicle state whose seven wheels (axles along y) move at ``velocity_mps`` and spin at
    ``spin_radps`` (the other fields do not enter the ratios)."""
    zeros = np.zeros((7, 3))
    return TrueState(
        base_m_enu=np.zeros(3), base_velocity_mps_enu=np.zeros(3), rotation=np.eye(3),
        hub_m_enu=zeros, hub_velocity_mps_enu=np.tile(velocity_mps, (7, 1)),
        wheel_spin_radps=np.full(7, spin_radps), motor_rate_radps=np.full(7, spin_radps),
        axle_enu=np.tile([0.0, 1.0, 0.0], (7, 1)), pen_m_enu=np.zeros(3),
        joint_angles_rad=np.zeros(2),
    )  # fmt: skip


@pytest.mark.parametrize(
    ("velocity", "spin", "slip"),
    [
        ((0.2, 0.0, 0.0), 0.2 / 0.066, 0.0),  # rolling forward
        ((-0.2, 0.0, 0.0), -0.2 / 0.066, 0.0),  # rolling backward (was 200 %, capped at 100 %)
        ((0.0, 0.0, 0.2), 0.2 / 0.066, 0.0),  # climbing a riser it spins up
        ((-0.1, 0.0, 0.0), -0.2 / 0.066, 0.5),  # backward, half its rim speed
        ((0.2, 0.0, 0.0), -0.2 / 0.066, 1.0),  # dragged against its spin: capped
    ],
)
def test_slip_is_signed_by_the_way_the_wheel_rolls(
    velocity: tuple[float, float, float], spin: float, slip: float
) -> None:
    ratios, _ = wheel_ratios(_rolling(np.array(velocity), spin), np.full(7, spin), RUBBER)
    np.testing.assert_allclose(ratios, slip, atol=1e-9)


def test_frames_touch_the_terrain_and_not_their_own_wheels() -> None:
    # a 0.14 m step whose edge lies under the rear frame, 0.1 m behind the middle axle: the rear
    # frame's plate (0.116-0.156 m above the floor) reaches into it
    world = OmniWorld(RUBBER, Terrain(steps=(Step(-0.1, 0.14),)), ((0.0, 0.0, 0.0, 0.0),))
    m, d = world.model, world.data
    pairs = {
        tuple(sorted((m.geom(c.geom1).name, m.geom(c.geom2).name))) for c in d.contact[: d.ncon]
    }
    assert ("step0", "v0_rear_frame") in pairs
    frames = {m.geom("v0_rear_frame").id, m.geom("v0_front_frame").id}
    rollers = set(np.flatnonzero(m.geom_contype == 1).tolist())
    for c in d.contact[: d.ncon]:
        assert not ({c.geom1, c.geom2} & frames and {c.geom1, c.geom2} & rollers)


@pytest.mark.slow
def test_no_step_is_climbed_through_the_body() -> None:
    # with the rear mass centre forward the model climbs 165-190 mm; 220 mm (once "climbed"
    # with no collision geometry on the frames) stops with the middle wheels on the riser, the
    # rear part reared up on its rear wheels and its frame's tail on the floor
    result = climb("proposed", 0.22, geometry=replace(RUBBER, rear_frame_com_x_m=-0.1075))
    assert not result.climbed


@pytest.mark.slow
def test_the_rear_mass_centre_decides_the_paper_step() -> None:
    # the finding of bench_ground: as read (-0.140 m) the rear wheels stall at the riser of the
    # 0.1 m step (front and middle wheels on top); read midway between the axles it is climbed
    as_read = climb("proposed", 0.1, geometry=RUBBER, time_limit_s=10.0)
    assert not as_read.climbed
    assert as_read.log["base_m_enu"][-1, 0] > STEP_EDGE_X_M  # the middle axle is up
    forward = climb("proposed", 0.1, geometry=replace(RUBBER, rear_frame_com_x_m=-0.1075))
    assert forward.climbed

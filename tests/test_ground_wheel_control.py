"""Wheel references from the body configuration (Chugo et al., eq. 1-20) against hand-computed
cases, the scaling rule as a property, and the flat-ground limit."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vehicles.omni_wheel.geometry import OmniGeometry
from vehicles.omni_wheel.wheel_control import (
    BodyConfiguration,
    chain_velocity,
    proposed_references,
    rotation_error_ratio,
    scale_to_running_speed,
    slip_ratio,
    standard_references,
    wheel_kinematics,
)

GEO = OmniGeometry()
R = 0.066
V0 = 0.25


def test_chain_velocity_is_rigid_motion() -> None:
    # wheel i at rest, link turning at 2 rad/s about z, next wheel 0.3 m ahead: 0.6 m/s to the left
    v = chain_velocity(np.zeros(3), np.array([0.0, 0.0, 2.0]), np.array([0.3, 0.0, 0.0]))
    np.testing.assert_allclose(v, [0.0, 0.6, 0.0])


def test_standard_method_is_v0_over_r_for_the_x_wheels() -> None:
    refs = standard_references(GEO)
    np.testing.assert_allclose(refs, [V0 / R, 0.0, V0 / R, V0 / R, V0 / R, V0 / R, V0 / R])
    np.testing.assert_allclose(standard_references(GEO, -1.0), -refs)


def test_rear_part_pitching_nose_up_hand_computed() -> None:
    # rear part pitching nose-up at 0.5 rad/s (-0.5 about y) while the middle axle runs at V0:
    # rear wheel (x = -0.215): v = (V0, 0, 0) + (0, q, 0) x (-0.215, 0, 0) = (V0, 0, 0.215 q)
    # joint 1 (x = 0.06): (V0, 0, -0.06 q); front wheel 0.195 further: (V0, 0, -0.255 q)
    q = -0.5
    config = BodyConfiguration(rear_rate_radps=(0.0, q, 0.0))
    kin = wheel_kinematics(np.array([V0, 0.0, 0.0]), config, GEO)
    np.testing.assert_allclose(kin.velocity_mps[5], [V0, 0.0, 0.215 * q], atol=1e-12)
    np.testing.assert_allclose(kin.velocity_mps[0], [V0, 0.0, -0.255 * q], atol=1e-12)
    refs = proposed_references(np.array([V0, 0.0, 0.0]), config, GEO)
    fastest = math.hypot(V0, 0.255 * q)  # the front wheels
    c = V0 / fastest
    assert refs.scale == pytest.approx(c)
    # eq. 17 in our frame: rolling speed / r minus the part's rate about the axle (y)
    assert refs.rate_radps[0] == pytest.approx(V0 / R - q)
    assert refs.rate_radps[3] == pytest.approx(c * V0 / R - q)
    assert refs.rate_radps[5] == pytest.approx(c * math.hypot(V0, 0.215 * q) / R - q)
    assert refs.rate_radps[1] == pytest.approx(0.0, abs=1e-12)  # sideways wheel: axle along x


def test_front_part_turning_alone_hand_computed() -> None:
    # the vehicle stands; the front part pitches nose-down about joint 1 at 1 rad/s: its wheels
    # move straight down at 0.195 m/s (alpha = 90 deg) and the motors must cancel the part's turn
    config = BodyConfiguration(joint_pitch_rate_radps=1.0)
    refs = proposed_references(np.zeros(3), config, GEO)
    np.testing.assert_allclose(refs.velocity_mps[0], [0.0, 0.0, -0.195], atol=1e-12)
    assert refs.rate_radps[0] == pytest.approx(0.195 / R - 1.0)
    assert refs.rate_radps[3] == pytest.approx(0.0, abs=1e-12)


def test_joint_angles_turn_the_front_axles() -> None:
    # front part rolled by 30 deg: the sideways wheel's drive direction tilts with it
    config = BodyConfiguration(joint_roll_rad=math.radians(30.0))
    kin = wheel_kinematics(np.array([0.0, 0.1, 0.0]), config, GEO)
    np.testing.assert_allclose(kin.drive[1], [0.0, math.cos(math.radians(30)), 0.5], atol=1e-12)


@settings(max_examples=60, deadline=None)
@given(
    st.lists(
        st.tuples(*(st.floats(-2.0, 2.0, allow_nan=False) for _ in range(3))),
        min_size=1,
        max_size=7,
    ),
    st.floats(0.05, 1.0),
)
def test_scaling_rule(rows: list[tuple[float, float, float]], v0: float) -> None:
    v = np.array(rows)
    scaled, c = scale_to_running_speed(v, v0)
    speed = np.linalg.norm(v, axis=1)
    assert 0.0 < c <= 1.0
    assert np.all(np.linalg.norm(scaled, axis=1) <= v0 * (1 + 1e-9))
    np.testing.assert_allclose(scaled, c * v)  # one factor for all wheels: directions kept
    if speed.max() <= v0:
        assert c == 1.0
    else:
        assert np.linalg.norm(scaled, axis=1).max() == pytest.approx(v0)


@settings(max_examples=60, deadline=None)
@given(st.floats(-0.3, 0.3), st.floats(-0.3, 0.3), st.floats(-0.6, 0.6))
def test_flat_ground_is_plain_omnidirectional_kinematics(vx: float, vy: float, wz: float) -> None:
    # on the flat every wheel's reference is its drive-direction speed over r, all scaled by one
    # factor when the fastest wheel would exceed V0
    config = BodyConfiguration(rear_rate_radps=(0.0, 0.0, wz))
    refs = proposed_references(np.array([vx, vy, 0.0]), config, GEO)
    v = np.array([vx, vy, 0.0])
    wheel_v = [v + np.cross([0.0, 0.0, wz], p) for p in GEO.wheel_positions_m()]
    fastest = max(float(np.linalg.norm(w)) for w in wheel_v)
    c = min(1.0, V0 / fastest) if fastest > 0.0 else 1.0
    drive = GEO.drive_directions()
    plain = np.array([d @ w / R for d, w in zip(drive, wheel_v, strict=True)])
    assert refs.scale == pytest.approx(c)
    np.testing.assert_allclose(refs.rate_radps, c * plain, atol=1e-12)


def test_slip_and_rotation_error_ratios() -> None:
    # r w = 0.25 m/s while the centre moves at 0.2 m/s: 20 % slip
    s = slip_ratio(R, np.array([0.25 / R]), np.array([0.2]))
    assert s[0] == pytest.approx(0.2)
    # reference 4 rad/s, wheel turns at 3.2 rad/s: 25 % rotation error
    assert rotation_error_ratio(np.array([4.0]), np.array([3.2]))[0] == pytest.approx(0.25)

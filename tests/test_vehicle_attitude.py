"""Each kind tells its body's attitude as the bus carries it, a unit quaternion (x, y, z, w)
body FLU -> world ENU (issue 36): the conversions against SciPy's, known attitudes of the
simulated vehicles, and MAVLink's NED/FRD ATTITUDE turned ENU/FLU."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from showfile import load_show
from vehicle_agent.backends.mavlink.frames import attitude_ned_to_xyzw_enu
from vehicles.attitude import quaternion_of_matrix, quaternion_of_wxyz, quaternions_of_euler
from vehicles.registry import vehicle_kind

ANGLE = st.floats(-math.pi, math.pi)
SHOW = load_show("shows/mixed.yaml")


def _same_rotation(a: object, b: object) -> bool:
    qa, qb = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return bool(np.allclose(qa, qb, atol=1e-9) or np.allclose(qa, -qb, atol=1e-9))


@given(roll=ANGLE, pitch=st.floats(-1.5, 1.5), yaw=ANGLE)
def test_euler_angles_turn_into_scipys_quaternion(roll: float, pitch: float, yaw: float) -> None:
    (q,) = quaternions_of_euler([[roll, pitch, yaw]])
    assert _same_rotation(q, Rotation.from_euler("ZYX", [yaw, pitch, roll]).as_quat())


@given(st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4).filter(
    lambda v: np.linalg.norm(v) > 0.1))  # fmt: skip
def test_a_matrix_turns_back_into_its_quaternion(v: list[float]) -> None:
    q = np.asarray(v) / np.linalg.norm(v)
    got = quaternion_of_matrix(Rotation.from_quat(q).as_matrix())
    assert _same_rotation(got, q) and got[3] >= 0.0
    assert quaternion_of_wxyz([q[3], q[0], q[1], q[2]]) == tuple(q)


def test_mavlinks_attitude_turns_enu_and_flu() -> None:
    north = attitude_ned_to_xyzw_enu(0.0, 0.0, 0.0)  # level, nose north: yaw +90 deg in ENU
    assert north == pytest.approx((0.0, 0.0, math.sqrt(0.5), math.sqrt(0.5)))
    nose_up = Rotation.from_quat(attitude_ned_to_xyzw_enu(0.0, 0.1, 0.0))  # NED pitch up
    assert nose_up.apply([1.0, 0.0, 0.0]) == pytest.approx((0.0, math.cos(0.1), math.sin(0.1)))
    right_down = Rotation.from_quat(attitude_ned_to_xyzw_enu(0.2, 0.0, math.pi / 2))
    # nose east, rolled right: the left wing (FLU y) rises, to north and up
    assert right_down.apply([0.0, 1.0, 0.0]) == pytest.approx((0.0, math.cos(0.2), math.sin(0.2)))


def test_the_wall_hexarotor_faces_its_wall_and_the_ground_writer_starts_level() -> None:
    calligrapher = SHOW.vehicle("calligrapher")
    kind = vehicle_kind(calligrapher.kind)
    settings = kind.settings(SHOW, calligrapher.id)
    state = kind.simulated_vehicle(calligrapher.home_m_enu, settings).state()
    assert state.attitude_xyzw_enu is not None
    arm_enu = Rotation.from_quat(state.attitude_xyzw_enu).apply([1.0, 0.0, 0.0])
    assert arm_enu == pytest.approx(-np.asarray(settings.surface.normal_enu), abs=1e-6)

    ground = SHOW.vehicle("ground1")
    kind = vehicle_kind(ground.kind)
    state = kind.simulated_vehicle(ground.home_m_enu, kind.settings(SHOW, ground.id)).state()
    assert state.attitude_xyzw_enu == pytest.approx((0.0, 0.0, 0.0, 1.0), abs=1e-6)

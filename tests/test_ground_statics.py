"""The ground writer's quasi-static climb bounds against hand-computed loads, and the readings
they ground in ``geometry`` (frame clearance, motor torque)."""

from __future__ import annotations

from dataclasses import replace

import pytest

from planner.limits import GRAVITY_MPS2
from vehicles.omni_wheel.geometry import OmniGeometry
from vehicles.omni_wheel.statics import (
    PAPER_CLIMB_M,
    axle_loads,
    min_frame_clearance_m,
    required_torque_nm,
    riser_phases,
    wheel_mass_kg,
)

GEO = OmniGeometry()


def test_axle_loads_carry_the_whole_vehicle() -> None:
    loads = axle_loads(GEO)
    total = loads.front_n + loads.middle_n + loads.rear_n
    assert total == pytest.approx((GEO.front_mass_kg + GEO.rear_mass_kg) * GRAVITY_MPS2)


def test_front_axle_carries_its_wheels_and_half_the_front_frame() -> None:
    # the front frame's mass centre in the middle of its linkage: half of it on the front axle
    wheel = wheel_mass_kg(GEO)
    frame = GEO.front_mass_kg - 3 * wheel
    expected = GRAVITY_MPS2 * (0.5 * frame + 3 * wheel)
    assert axle_loads(GEO).front_n == pytest.approx(expected)


def test_rear_mass_centre_moving_forward_loads_the_middle_axle() -> None:
    forward = axle_loads(replace(GEO, rear_frame_com_x_m=-0.1075))
    as_read = axle_loads(GEO)
    assert forward.middle_n > as_read.middle_n
    assert forward.rear_n < as_read.rear_n


def test_table_1_friction_cannot_lift_any_axle_up_a_riser() -> None:
    # the paper's 0.3: mu^2 of the pushing wheels' load is far below each axle's load
    phases = riser_phases(GEO, GEO.friction_static)
    assert not any(p.possible for p in phases)
    front = phases[0]
    assert front.lift_available_n == pytest.approx(
        0.09 * (axle_loads(GEO).middle_n + axle_loads(GEO).rear_n)
    )


def test_rubber_rollers_can_lift_each_axle_quasi_statically() -> None:
    assert all(p.possible for p in riser_phases(GEO, 1.0))


def test_motor_torque_covers_the_paper_climb_under_either_reading() -> None:
    other = replace(GEO, rear_frame_com_x_m=-0.1075)
    assert required_torque_nm(GEO) == pytest.approx(0.5 * axle_loads(GEO).middle_n * 0.066)
    assert GEO.motor_torque_max_nm >= max(required_torque_nm(GEO), required_torque_nm(other))
    assert GEO.motor_torque_max_nm < 1.05 * required_torque_nm(other)  # the bound, not a margin


def test_frames_clear_the_paper_climb_and_not_much_more() -> None:
    bound = min_frame_clearance_m(GEO, PAPER_CLIMB_M)
    assert bound <= GEO.frame_clearance_m < bound + 0.005
    # a lower step needs less; a flat floor none
    assert min_frame_clearance_m(GEO, 0.1) < bound
    assert min_frame_clearance_m(GEO, 0.0) == 0.0

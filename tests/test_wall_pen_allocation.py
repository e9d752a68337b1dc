"""The sponge pen's force <-> width curve and the hexarotor's wrench allocation."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.errors import PlannerError
from vehicles.hexarotor_sponge.allocation import Allocator, rotor_geometry
from vehicles.hexarotor_sponge.params import GRAVITY_MPS2, HexarotorParams
from vehicles.hexarotor_sponge.pen import PenCurve

PEN = PenCurve()
PARAMS = HexarotorParams()


def test_pen_curve_known_points() -> None:
    # width = 2 + 3.2 F - 0.2 F^2 mm: 5.0 mm at 1 N, 14.0 mm at 6 N, 10.0 mm at 3.13 N.
    assert PEN.width_m(np.array([1.0, 6.0])) == pytest.approx([5.0e-3, 14.0e-3])
    assert PEN.width_min_m == pytest.approx(5.0e-3)
    assert PEN.width_max_m == pytest.approx(14.0e-3)
    assert PEN.width_m(np.array([0.0, -1.0])).tolist() == [0.0, 0.0]


@settings(max_examples=40, deadline=None)
@given(st.floats(min_value=1.0, max_value=6.0))
def test_pen_round_trip_force_width_force(force_n: float) -> None:
    width = PEN.width_m(np.array([force_n]))
    assert PEN.force_n(width)[0] == pytest.approx(force_n, abs=1e-9)


def test_width_out_of_range_is_an_error_naming_the_point() -> None:
    with pytest.raises(PlannerError, match=r"point 2.*20.00 mm is outside the pen's range"):
        PEN.force_n(np.array([6e-3, 7e-3, 20e-3]))
    clamped, changed = PEN.clamp_width_m(np.array([1e-3, 8e-3, 20e-3]))
    assert changed == 2
    assert clamped.tolist() == pytest.approx([5e-3, 8e-3, 14e-3])


def test_a_decreasing_curve_is_refused() -> None:
    with pytest.raises(PlannerError, match="grow with force"):
        PenCurve(coefficients_m=(10e-3, -1e-3))


def test_rotors_are_tilted_unit_axes() -> None:
    geo = rotor_geometry(PARAMS)
    assert np.linalg.norm(geo.axis_body, axis=1) == pytest.approx(np.ones(6))
    assert geo.axis_body[:, 2] == pytest.approx(np.full(6, np.cos(PARAMS.rotor_tilt_rad)))


def test_hover_is_six_equal_thrusts() -> None:
    alloc = Allocator(PARAMS)
    weight = PARAMS.mass_kg * GRAVITY_MPS2
    out = alloc.allocate(np.array([0.0, 0.0, weight, 0.0, 0.0, 0.0]))
    assert not out.saturated
    expected = weight / 6.0 / np.cos(PARAMS.rotor_tilt_rad)
    assert out.thrust_n == pytest.approx(np.full(6, expected))


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.floats(min_value=-4.0, max_value=4.0), min_size=3, max_size=3),
    st.lists(st.floats(min_value=-0.5, max_value=0.5), min_size=3, max_size=3),
)
def test_allocation_round_trip_within_limits(force: list[float], torque: list[float]) -> None:
    alloc = Allocator(PARAMS)
    wrench = np.array([force[0], force[1], 30.0 + force[2], *torque])
    out = alloc.allocate(wrench)
    assert not out.saturated
    assert np.all(out.thrust_n >= 0.0) and np.all(out.thrust_n <= PARAMS.thrust_max_n)
    assert alloc.wrench(out.thrust_n) == pytest.approx(wrench, abs=1e-9)


def test_allocation_beyond_limits_saturates_and_keeps_torque() -> None:
    alloc = Allocator(PARAMS)
    wrench = np.array([30.0, 0.0, 35.0, 0.0, 0.0, 0.2])
    out = alloc.allocate(wrench)
    assert out.saturated
    assert np.all(out.thrust_n >= -1e-12) and np.all(out.thrust_n <= PARAMS.thrust_max_n + 1e-12)
    got = alloc.wrench(out.thrust_n)
    assert got[0] < 30.0
    assert got[3:] == pytest.approx(wrench[3:], abs=0.01)

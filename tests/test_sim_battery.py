"""The LiPo pack model and the simulated vehicle's battery: known answers worked by hand,
finite differences, properties."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sim.battery import (
    LipoPack,
    cell_energy_wh_per_ah,
    cell_open_circuit_v,
    discharge,
    full,
    minutes_left,
)
from sim.errors import SimError
from sim.rotor_power import rotor_power_w
from vehicle_agent.backends.base import BackendError
from vehicle_agent.backends.sim import SimVehicle
from vehicles.batteries import kind_battery

PACK_4S = LipoPack(cells_in_series=4, capacity_mah=3000.0, cell_resistance_ohm=0.008)


def test_cell_voltage_is_chen_and_rincon_moras_curve_at_its_ends() -> None:
    # by hand: 3.685 + 0.2156 - 0.1178 + 0.3201 = 4.1029 (the exponential is 1e-15 at soc 1)
    assert cell_open_circuit_v(1.0) == pytest.approx(4.1029, abs=1e-9)
    assert cell_open_circuit_v(0.0) == pytest.approx(3.685 - 1.031, abs=1e-9)
    assert cell_open_circuit_v(0.5) == pytest.approx(3.685 + 0.1078 - 0.02945 + 0.0400125, abs=1e-6)


@pytest.mark.parametrize("soc", [0.01, 0.05, 0.2, 0.5, 0.8, 0.99])
def test_the_energy_curve_is_the_integral_of_the_voltage(soc: float) -> None:
    h = 1e-6
    slope = (cell_energy_wh_per_ah(soc + h) - cell_energy_wh_per_ah(soc - h)) / (2 * h)
    assert slope == pytest.approx(cell_open_circuit_v(soc), rel=1e-7)
    assert cell_energy_wh_per_ah(0.0) == 0.0


def test_hover_power_of_the_airshow_quadrotor_worked_by_hand() -> None:
    # per rotor T = 9.81 / 4 = 2.4525 N, A = pi 0.127^2 = 0.050671 m^2,
    # P_ideal = 2.4525^1.5 / sqrt(2 * 1.225 * 0.050671) = 3.84073 / 0.352352 = 10.9002 W;
    # four rotors 43.601 W, over FM 0.55 and drive 0.80: 99.09 W
    assert rotor_power_w(9.81, 4, 0.127) == pytest.approx(99.09, rel=1e-3)
    assert rotor_power_w(0.0, 4, 0.127) == 0.0
    battery = kind_battery("quadrotor-brush")
    assert battery.power_w.hover_w == pytest.approx(99.09 + 6.0, rel=1e-3)


def test_a_minute_of_hover_from_a_full_pack_worked_by_hand() -> None:
    # V_oc = 4 x 4.1029 = 16.4116 V full, R = 4 x 8 mOhm; P = 105.0967 W:
    # I = (16.4116 - sqrt(16.4116^2 - 4 x 0.032 x 105.0967)) / (2 x 0.032) = 6.4838 A at first;
    # the curve's slope at full charge, 4 x (0.2156 - 2 x 0.1178 + 3 x 0.3201) = 3.761 V, over
    # the 3.6 % drawn lowers V_oc by 0.136 V: at the minute's middle V_oc = 16.3438 V and
    # I = 105.0967 / (16.3438 - 0.032 x 6.513) = 6.513 A: 6.513 x 60 / 3.6 = 108.55 mAh
    # (3.618 % of 3000 mAh); 105.0967 W x 60 s = 1.7516 Wh at the terminals
    power_w = kind_battery("quadrotor-brush").power_w.hover_w
    state = full(PACK_4S)
    for _ in range(6000):
        state = discharge(PACK_4S, state, power_w, 0.01)
    assert state.drawn_mah == pytest.approx(108.55, rel=1e-3)
    assert 1.0 - state.charge_fraction == pytest.approx(0.03618, rel=1e-3)
    assert state.drawn_wh == pytest.approx(105.0967 / 60, rel=2e-3)
    sag_v = PACK_4S.open_circuit_v(state.charge_fraction) - state.voltage_v
    assert sag_v == pytest.approx(state.current_a * 0.032, rel=1e-9)


def test_minutes_left_of_a_full_pack_worked_by_hand() -> None:
    # E = 12 Ah-cells x 3.804101 Wh/Ah = 45.649 Wh; the resistance keeps
    # (16.4116 - 6.4838 x 0.032) / 16.4116 = 0.98736 of it: 45.072 Wh / 105.0967 W = 25.73 min
    assert PACK_4S.energy_wh() == pytest.approx(45.649, rel=1e-4)
    assert minutes_left(PACK_4S, 1.0, 105.0967) == pytest.approx(25.73, rel=1e-3)


def test_a_pack_refuses_figures_it_cannot_have() -> None:
    with pytest.raises(SimError, match="cells_in_series"):
        LipoPack(cells_in_series=0, capacity_mah=3000.0, cell_resistance_ohm=0.008)
    with pytest.raises(SimError, match="capacity_mah"):
        LipoPack(cells_in_series=4, capacity_mah=-1.0, cell_resistance_ohm=0.008)
    with pytest.raises(SimError, match="power_w"):
        PACK_4S.current_a(0.5, -10.0)


@settings(max_examples=200, deadline=None)
@given(
    steps=st.lists(st.tuples(st.floats(0.0, 2000.0), st.floats(0.0, 5.0)), min_size=1, max_size=40)
)
def test_charge_never_rises_and_the_terminal_voltage_never_exceeds_the_open_circuit_one(
    steps: list[tuple[float, float]],
) -> None:
    state = full(PACK_4S)
    for power_w, dt_s in steps:
        after = discharge(PACK_4S, state, power_w, dt_s)
        assert after.charge_fraction <= state.charge_fraction
        assert after.charge_fraction >= 0.0
        assert after.voltage_v <= PACK_4S.open_circuit_v(after.charge_fraction) + 1e-12
        assert after.drawn_mah >= state.drawn_mah
        state = after


@pytest.mark.parametrize("kind", ["quadrotor-brush", "omni-wheel"])
def test_the_simulated_vehicle_draws_its_kinds_power_in_each_phase(kind: str) -> None:
    from vehicles.registry import vehicle_kind

    vehicle = SimVehicle((0.0, 0.0, 0.0), kind=vehicle_kind(kind))
    battery = vehicle.battery
    resting = [vehicle.tick(None) for _ in range(100)]
    assert vehicle.phase() == "rest"
    assert resting[-1].battery_fraction is not None and resting[-1].battery_fraction < 1.0
    drawn = vehicle.battery_state.drawn_wh
    assert drawn == pytest.approx(battery.power_w.rest_w * 100 * vehicle.dt_s / 3600, rel=1e-6)
    vehicle.takeoff((0.0, 0.0, 1.0))
    for _ in range(200):
        snap = vehicle.tick(None)
    assert vehicle.phase() == "hover"
    hover_wh = vehicle.battery_state.drawn_wh - drawn
    assert hover_wh == pytest.approx(battery.power_w.hover_w * 200 * vehicle.dt_s / 3600, rel=1e-3)
    assert snap.battery_voltage_v is not None
    assert snap.battery_voltage_v < battery.pack.open_circuit_v(snap.battery_fraction or 0.0)
    assert snap.battery_minutes_left == pytest.approx(
        minutes_left(battery.pack, vehicle.battery_state.charge_fraction,
                     battery.power_w.of(battery.cruise)),
    )  # fmt: skip
    with pytest.raises(BackendError, match="not at rest"):
        vehicle.swap_battery()


def test_a_swap_on_the_ground_gives_a_full_pack() -> None:
    vehicle = SimVehicle((0.0, 0.0, 0.0))
    vehicle.battery_state = discharge(vehicle.battery.pack, vehicle.battery_state, 500.0, 600.0)
    assert vehicle.snapshot().battery_fraction == pytest.approx(
        vehicle.battery_state.charge_fraction
    )
    vehicle.swap_battery()
    snap = vehicle.snapshot()
    assert snap.battery_fraction == 1.0
    assert snap.battery_voltage_v == pytest.approx(vehicle.battery.pack.open_circuit_v(1.0))
    assert math.isfinite(snap.battery_minutes_left or math.nan)

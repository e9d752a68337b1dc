"""mavsim's battery: drawn by the airframe's own thrust on the pack model, sent as each
autopilot sends BATTERY_STATUS and SYS_STATUS, and read back by the agent's MAVLink state from
the bytes."""

from __future__ import annotations

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from mavsim.autopilot import Autopilot
from mavsim.autopilot_core import Result
from mavsim.config import VehicleConfig
from mavsim.modes import CopterMode
from mavsim.params import Flavor
from mavsim.px4 import Px4Autopilot
from sim.rotor_power import rotor_power_w
from vehicle_agent.backends.mavlink.state import LinkState
from vehicles.quadrotor_brush.battery import AVIONICS_W, PACK


def _hovering(seconds: float) -> Autopilot:
    """An ArduCopter hovering at 0.8 m for about ``seconds`` [s] (PX4 draws the same pack)."""
    config = VehicleConfig(vehicle_id="v", system_id=7, port=0, home_m_enu=(0.0, 0.0, 0.0))
    ap = Autopilot(config)
    t = 0.0

    def run(s: float) -> None:
        nonlocal t
        for _ in range(round(s / ap.airframe.dt_s)):
            t += ap.airframe.dt_s
            ap.step(t)

    run(config.position_source_delay_s + 0.1)
    assert ap.set_mode(CopterMode.GUIDED) == Result.ACCEPTED
    assert ap.arm() == Result.ACCEPTED
    assert ap.takeoff(0.8) == Result.ACCEPTED
    run(seconds)
    return ap


def _wire(*messages: mavlink.MAVLink_message) -> list[mavlink.MAVLink_message]:
    """Pack as the vehicle (system 7) sends, parse the bytes as a ground station does."""
    sender = mavlink.MAVLink(None, srcSystem=7, srcComponent=1)
    data = b"".join(m.pack(sender) for m in messages)
    parsed = mavlink.MAVLink(None, srcSystem=255, srcComponent=190).parse_buffer(data)
    received: list[mavlink.MAVLink_message] = list(parsed or [])
    assert len(received) == len(messages)
    assert [m.get_type() for m in received] == [m.get_type() for m in messages]
    return received


@pytest.mark.parametrize("autopilot", ["ardupilot", "px4"])
def test_battery_status_bytes_carry_the_pack_model_and_the_agent_reads_them(
    autopilot: Flavor,
) -> None:
    ap = _hovering(30.0)
    battery, mav = ap.battery, mavlink.MAVLink(None, srcSystem=7, srcComponent=1)
    heartbeat = mav.heartbeat_encode(mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_PX4
                                     if autopilot == "px4" else mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA,
                                     0, 0, mavlink.MAV_STATE_ACTIVE)  # fmt: skip
    _, status, sys_status = _wire(
        heartbeat, battery.battery_status(mav, autopilot), battery.sys_status(mav, 0, 0)
    )
    state = battery.state
    # hovering 30 s: thrust near the weight, so the current near the model's hover current
    hover_w = AVIONICS_W + rotor_power_w(ap.config.mass_kg * 9.81, 4, 0.127)
    hover_a = PACK.current_a(state.charge_fraction, hover_w)
    assert state.current_a == pytest.approx(hover_a, rel=0.05)
    assert 0.96 < state.charge_fraction < 0.995  # about 30-40 s of hover drawn
    assert status.get_type() == "BATTERY_STATUS"
    assert status.battery_remaining == round(100 * state.charge_fraction)
    assert status.current_battery == int(state.current_a * 100)
    assert status.current_consumed == int(state.drawn_mah)
    assert status.time_remaining == int(state.charge_fraction * 3000 * 3.6 / state.current_a)
    assert status.charge_state == mavlink.MAV_BATTERY_CHARGE_STATE_OK
    pack_mv = int(state.voltage_v * 1000)
    if autopilot == "ardupilot":  # the pack in the first cell, energy in hJ
        assert list(status.voltages) == [pack_mv] + [65535] * 9
        assert status.energy_consumed == int(state.drawn_wh * 36)
    else:  # each of its four cells, no energy
        assert list(status.voltages) == [pack_mv // 4] * 4 + [65535] * 6
        assert status.energy_consumed == -1
    assert sys_status.voltage_battery == pack_mv
    assert sys_status.battery_remaining == status.battery_remaining

    link = LinkState(7)
    for message in _wire(heartbeat, battery.battery_status(mav, autopilot)):
        link.absorb(message)
    assert link.battery_fraction == pytest.approx(status.battery_remaining / 100)
    cells_v = pack_mv / 1000 if autopilot == "ardupilot" else 4 * (pack_mv // 4) / 1000
    assert link.battery_voltage_v == pytest.approx(cells_v)
    assert link.battery_minutes_left == pytest.approx(status.time_remaining / 60)


def test_a_disarmed_autopilot_draws_its_avionics_only_and_px4_warns_by_its_thresholds() -> None:
    config = VehicleConfig(vehicle_id="v", system_id=7, port=0, home_m_enu=(0.0, 0.0, 0.0))
    ap = Autopilot(config)
    for i in range(100):
        ap.step((i + 1) * ap.airframe.dt_s)
    assert ap.battery.state.current_a == pytest.approx(PACK.current_a(1.0, AVIONICS_W), rel=1e-3)
    px4 = VehicleConfig(vehicle_id="v", system_id=7, port=0, home_m_enu=(0.0, 0.0, 0.0),
                        autopilot="px4")  # fmt: skip
    battery = Px4Autopilot(px4).battery
    for charge, expected in ((0.5, mavlink.MAV_BATTERY_CHARGE_STATE_OK),
                             (0.14, mavlink.MAV_BATTERY_CHARGE_STATE_LOW),
                             (0.06, mavlink.MAV_BATTERY_CHARGE_STATE_CRITICAL),
                             (0.04, mavlink.MAV_BATTERY_CHARGE_STATE_EMERGENCY)):  # fmt: skip
        battery.state = type(battery.state)(charge_fraction=charge, voltage_v=15.0)
        assert battery.charge_state("px4") == expected


def test_ardupilots_battery_reset_sets_its_count_and_a_fresh_pack_only_on_the_ground() -> None:
    ap = _hovering(5.0)  # armed, in the air
    mav = mavlink.MAVLink(None, srcSystem=7, srcComponent=1)
    pack_before = ap.battery.state
    assert ap.battery_reset(0b10, 100.0) == Result.ACCEPTED  # a battery it lacks: ignored
    assert ap.battery.state == pack_before and ap.battery.counted_mah == 0.0
    # in the air: accepted, as ArduPilot does; only its count says full, the pack is the same
    assert ap.battery_reset(0b1, 150.0) == Result.ACCEPTED  # clamped to 100 %
    (status,) = _wire(ap.battery.battery_status(mav, "ardupilot"))
    assert status.battery_remaining == 100 and status.current_consumed == 0
    assert status.energy_consumed == 0
    assert ap.battery.state.charge_fraction == pack_before.charge_fraction
    assert status.voltages[0] == int(pack_before.voltage_v * 1000)
    # disarmed on the ground at 80 %: the count and mavsim's pack, ArduPilot's energy estimate
    ground = Autopilot(ap.config)
    ground.step(ground.airframe.dt_s)
    volts = ground.battery.state.voltage_v
    assert ground.battery_reset(0xFFFF, 80.0) == Result.ACCEPTED
    (status,) = _wire(ground.battery.battery_status(mav, "ardupilot"))
    assert status.battery_remaining == 80 and status.current_consumed == 600
    assert status.energy_consumed == int(600 * 0.001 * volts * 36)
    assert ground.battery.state.charge_fraction == 0.8


def test_px4_has_no_battery_reset_and_is_full_again_once_disarmed() -> None:
    px4 = VehicleConfig(vehicle_id="v", system_id=7, port=0, home_m_enu=(0.0, 0.0, 0.0),
                        autopilot="px4")  # fmt: skip
    ap = Px4Autopilot(px4)
    assert ap.battery_reset(0b1, 100.0) == Result.UNSUPPORTED
    ap.battery.state = type(ap.battery.state)(charge_fraction=0.4, voltage_v=15.0, drawn_mah=1800)
    ap.step(ap.airframe.dt_s)
    assert not ap.armed and ap.battery.remaining_percent == 100
    assert ap.battery.state.charge_fraction == 1.0 and ap.battery.state.drawn_mah == 0.0

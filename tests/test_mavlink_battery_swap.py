"""The crew's battery swap on a MAVLink vehicle, over real MAVLink bytes with mavsim: ArduPilot is
told with MAV_CMD_BATTERY_RESET (on the ground, disarmed) and reports the full pack; PX4 has no
such command and its simulated pack is full again once disarmed (PX4 SITL's battery simulator)."""

from __future__ import annotations

import asyncio
from dataclasses import replace

import pytest
from test_mavlink_backend import Driver, airborne, connected, vehicle

from mavsim.server import MavsimServer
from sim.battery import full
from vehicle_agent.backends.base import BackendError, BatterySwap
from vehicle_agent.backends.mavlink.backend import MavlinkBackend
from vehicle_agent.backends.mavlink.battery import CMD_BATTERY_RESET
from vehicle_agent.backends.mavlink.errors import CommandRejectedError
from vehicles.quadrotor_brush.battery import PACK

pytestmark = pytest.mark.timeout(60)

MAV_RESULT_ACCEPTED, MAV_RESULT_UNSUPPORTED = 0, 3


def _drain(server: MavsimServer, charge_fraction: float) -> None:
    """mavsim's pack down to ``charge_fraction``, as if flown there (its count included)."""
    battery = server.endpoints[0].autopilot.battery
    drawn_mah = (1.0 - charge_fraction) * PACK.capacity_mah
    battery.state = replace(full(PACK), charge_fraction=charge_fraction, drawn_mah=drawn_mah,
                            voltage_v=PACK.open_circuit_v(charge_fraction))  # fmt: skip


def _answers(backend: MavlinkBackend, command: int) -> list[int]:
    return [result for sent, result in backend.state.acks if sent == command]


async def _reports(driver: Driver, fraction: float) -> None:
    await driver.until(lambda s: s.battery_fraction == pytest.approx(fraction, abs=0.011), 4.0)


def test_ardupilot_is_told_of_the_fresh_pack_and_reports_it() -> None:
    async def scenario(server: MavsimServer) -> None:
        _drain(server, 0.3)
        async with connected(server) as (backend, driver):
            assert isinstance(backend, BatterySwap)
            await _reports(driver, 0.3)
            await backend.swap_battery()
            assert _answers(backend, CMD_BATTERY_RESET) == [MAV_RESULT_ACCEPTED]
            await _reports(driver, 1.0)
            pack = server.endpoints[0].autopilot.battery.state
            assert pack.charge_fraction == pytest.approx(1.0, abs=1e-3)  # the crew's, in mavsim
            assert backend.state.battery_voltage_v == pytest.approx(PACK.open_circuit_v(1.0), 0.01)

    with vehicle() as server:
        asyncio.run(scenario(server))


def test_an_airborne_vehicle_is_not_told_of_a_swap() -> None:
    async def scenario(server: MavsimServer) -> None:
        async with connected(server) as (backend, driver):
            await airborne(backend, driver)
            _drain(server, 0.5)
            await _reports(driver, 0.5)
            with pytest.raises(BackendError, match="its motors are armed"):
                await backend.swap_battery()
            await driver.tick()
            assert _answers(backend, CMD_BATTERY_RESET) == []
            assert server.endpoints[0].autopilot.battery.remaining_percent == 50

    with vehicle() as server:
        asyncio.run(scenario(server))


def test_px4_refuses_the_reset_and_its_pack_is_full_once_disarmed() -> None:
    async def scenario(server: MavsimServer) -> None:
        async with connected(server) as (backend, driver):
            await airborne(backend, driver)
            _drain(server, 0.4)  # armed: PX4 SITL's pack drains, no refill
            await _reports(driver, 0.4)
            await backend.land()
            await driver.until(lambda s: s.mode == "idle", 6.0)
            await _reports(driver, 1.0)  # disarmed: full again, the swap ends by itself
            await backend.swap_battery()  # the crew's confirmation sends nothing to PX4
            await driver.tick()
            assert _answers(backend, CMD_BATTERY_RESET) == []
            with pytest.raises(CommandRejectedError) as refused:  # as PX4's Commander answers
                await backend.commands.run(CMD_BATTERY_RESET, 1.0, 100.0)
            assert refused.value.result == MAV_RESULT_UNSUPPORTED

    with vehicle(autopilot="px4") as server:
        asyncio.run(scenario(server))

"""The agent's battery: its status carries the backend's battery, rounded so that a status sent
on change goes out when a figure a person reads changes; the crew's swap reaches the simulator."""

from __future__ import annotations

import asyncio

from bus.messages import VehicleStatus
from sim.battery import discharge
from vehicle_agent.backends.sim import SimBackend, SimVehicle
from vehicle_agent.battery import swap_battery, with_battery

STATUS = VehicleStatus(vehicle_id="uav1", kind="quadrotor-brush", state="idle")


def test_the_status_carries_the_battery_rounded() -> None:
    vehicle = SimVehicle((0.0, 0.0, 0.0))
    vehicle.battery_state = discharge(vehicle.battery.pack, vehicle.battery_state, 105.0, 300.0)
    snap = vehicle.tick(None)  # at rest: the avionics' draw
    status = with_battery(STATUS, snap)
    assert status.battery_fraction == round(snap.battery_fraction or 0.0, 2)
    assert status.battery_voltage_v == round(snap.battery_voltage_v or 0.0, 1)
    assert status.battery_minutes_left == round(snap.battery_minutes_left or 0.0, 1)
    # another tick at rest changes no figure shown: the status is not sent again
    ticked = with_battery(STATUS, vehicle.tick(None))
    assert ticked == status
    assert with_battery(STATUS, None) == STATUS


def test_the_crews_swap_fills_a_simulated_pack_and_is_refused_in_the_air() -> None:
    vehicle = SimVehicle((0.0, 0.0, 0.0))
    backend = SimBackend(vehicle)
    vehicle.battery_state = discharge(vehicle.battery.pack, vehicle.battery_state, 105.0, 600.0)
    reply = asyncio.run(swap_battery(backend, "uav1"))
    assert reply.ok and vehicle.battery_state.charge_fraction == 1.0
    vehicle.takeoff((0.0, 0.0, 1.0))
    vehicle.tick(None)
    refused = asyncio.run(swap_battery(backend, "uav1"))
    assert not refused.ok and refused.error is not None and "not at rest" in refused.message
    told = asyncio.run(swap_battery(object(), "uav2"))  # an autopilot's battery is its own
    assert told.ok and told.message == "uav2: battery read from its autopilot"

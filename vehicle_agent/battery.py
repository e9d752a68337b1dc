"""The battery in the agent's status, and the crew's swap carried out on the backend (pure but
for the swap's one backend call)."""

from __future__ import annotations

import msgspec

from bus.messages import CommandReply, ErrorInfo, VehicleStatus
from vehicle_agent.backends.base import BackendError, BatterySwap, VehicleSnapshot


def with_battery(status: VehicleStatus, snapshot: VehicleSnapshot | None) -> VehicleStatus:
    """``status`` with the battery of ``snapshot``, rounded (percent, 0.1 V, 0.1 min) so that a
    status published on change goes out when a figure a person reads changes, not every tick."""
    if snapshot is None or snapshot.battery_fraction is None:
        return status
    return msgspec.structs.replace(
        status,
        battery_fraction=round(snapshot.battery_fraction, 2),
        battery_voltage_v=_rounded(snapshot.battery_voltage_v, 1),
        battery_minutes_left=_rounded(snapshot.battery_minutes_left, 1),
    )


def _rounded(value: float | None, digits: int) -> float | None:
    return None if value is None else round(value, digits)


async def swap_battery(backend: object, vehicle_id: str) -> CommandReply:
    """The crew's ``battery_swapped``, only at rest on the ground: a simulated vehicle gets a
    full pack, an autopilot is told (ArduPilot: MAV_CMD_BATTERY_RESET); a backend without a
    battery of its own has nothing to do."""
    if not isinstance(backend, BatterySwap):
        return CommandReply(ok=True, message=f"{vehicle_id}: battery read from its autopilot")
    try:
        await backend.swap_battery()
    except BackendError as exc:
        info = ErrorInfo(code="bad_state", message=str(exc))
        return CommandReply(ok=False, message=info.message, error=info)
    return CommandReply(ok=True, message=f"{vehicle_id}: fresh battery")

"""Each kind's battery (:class:`sim.battery.VehicleBattery`): its pack and what it draws per
phase, from its room's ``battery.py`` (``vehicles/<room>/battery.py``, ``BATTERY``), imported on
first use (light: no MuJoCo, no CasADi)."""

from __future__ import annotations

import importlib
from functools import cache

from sim.battery import VehicleBattery
from vehicles import ROOMS, UnknownKindError


@cache
def kind_battery(kind: str) -> VehicleBattery:
    """The battery of vehicles of ``kind``; raises :class:`vehicles.UnknownKindError`."""
    room = ROOMS.get(kind)
    if room is None:
        raise UnknownKindError(kind)
    package = room.kind_module.rsplit(".", 1)[0]
    battery: VehicleBattery = importlib.import_module(f"{package}.battery").BATTERY
    return battery

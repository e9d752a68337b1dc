"""The kind of a show file's ``kind`` name: its room, imported on first use."""

from __future__ import annotations

import importlib

from vehicles import ROOMS, UnknownKindError
from vehicles.kind import VehicleKind


def vehicle_kind(name: str) -> VehicleKind:
    """The kind called ``name`` (its room imported on first use); UnknownKindError if none."""
    room = ROOMS.get(name)
    if room is None:
        raise UnknownKindError(name)
    kind: VehicleKind = importlib.import_module(room.kind_module).KIND
    return kind

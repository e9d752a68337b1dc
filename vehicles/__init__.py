"""Vehicle kinds: one room each (``vehicles/<kind>/``) behind :class:`vehicles.kind.VehicleKind`.

The registry maps a show file's ``kind`` to its room, imported only when first asked for (a room
may pull in MuJoCo or CasADi) by :func:`vehicles.registry.vehicle_kind`. This module imports
nothing, so the show file can name the kinds without the console or trust seeing the planner.
"""

from __future__ import annotations

ROOMS: dict[str, str] = {
    "quadrotor-brush": "vehicles.quadrotor_brush.kind",
    "omni-wheel": "vehicles.omni_wheel.kind",
    "hexarotor-sponge": "vehicles.hexarotor_sponge.kind",
}
"""Kind name (as in show files) -> the module whose ``KIND`` implements it."""


class UnknownKindError(LookupError):
    """A vehicle kind without a room; the message names the kinds that exist."""

    def __init__(self, name: str) -> None:
        self.name = name
        super().__init__(f"no vehicle kind {name!r}; the kinds are: {', '.join(sorted(ROOMS))}")


def kind_names() -> tuple[str, ...]:
    """The kinds that have a room, sorted."""
    return tuple(sorted(ROOMS))

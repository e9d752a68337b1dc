"""Vehicle kinds: one room each (``vehicles/<kind>/``) behind :class:`vehicles.kind.VehicleKind`.

:data:`ROOMS` is the one registry of the kinds: per kind a :class:`Room` record of plain data,
what the show file and the registry know of the kind without importing its room. The kind object
itself (``KIND``, which may pull in MuJoCo or CasADi) is imported only when first asked for, by
:func:`vehicles.registry.vehicle_kind`. This module imports nothing, so the show file can name
the kinds, and check a vehicle against its kind, without the console or trust seeing the planner.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

if TYPE_CHECKING:
    from vehicles.surface import Orientation


@dataclass(frozen=True)
class Room:
    """What is known of a vehicle kind without importing its room (plain data).

    The kind object is the truth at run time; tests hold its ``orientation``
    (tests/test_showfile_kinds.py) and ``autopilot_world`` (tests/test_showfile_load.py) to this
    record."""

    kind_module: str
    """The module whose ``KIND`` implements the kind (imported on first use)."""
    orientation: Orientation
    """The surface it writes on: a board's ``orientation`` in a show file."""
    footprint_radius_m: float
    """Radius in [m] of a circle about the vehicle's home point that holds its whole plan view
    (rotor tips, wheels, arm): two homes closer than the sum of their kinds' radii are refused
    (tests/test_showfile_kinds.py holds each against its room's dimensions)."""
    autopilot: bool = False
    """A MAVLink autopilot can fly it (``backend: mavlink``); False: the sim backend only."""
    section: str | None = None
    """Key of the kind's own section of a show file (a ``showfile.models.Show`` field typed by a
    model of the room's ``show_section`` module); None: the kind has none."""
    show_checks: str | None = None
    """A light module of the room (pydantic and plain Python only: the show file loads it) whose
    ``board_problem(show, vehicle, board) -> str | None`` says in one line why a vehicle of the
    kind cannot write on its board (beyond its reach, behind a step); None: no check of its own."""
    transit_route: Literal["straight", "sideways_first"] = "straight"
    """How its pen-up moves run (the kind's ``JobPhases.route``), which shapes its geofence
    (``showfile.geofence.show_fence``)."""


ROOMS: dict[str, Room] = {
    "quadrotor-brush": Room(
        kind_module="vehicles.quadrotor_brush.kind",
        orientation="horizontal",
        footprint_radius_m=0.33,  # Airshow: 40 cm motor to motor, 10-inch propellers
        autopilot=True,
    ),
    "omni-wheel": Room(
        kind_module="vehicles.omni_wheel.kind",
        orientation="floor",
        footprint_radius_m=0.5,  # home is the marker; the rear wheels reach 0.44 m behind it
        section="omni_wheel",
        show_checks="vehicles.omni_wheel.show_section",
        transit_route="sideways_first",
    ),
    "hexarotor-sponge": Room(
        kind_module="vehicles.hexarotor_sponge.kind",
        orientation="vertical",
        footprint_radius_m=0.45,  # rotors 0.28 m out, the pen's arm 0.40 m
        section="hexarotor",
        show_checks="vehicles.hexarotor_sponge.show_section",
    ),
}
"""Kind name (as in show files) -> its room's record."""

DEFAULT_KIND = "quadrotor-brush"
"""The kind meant where none is named: a show file's vehicle without ``kind``, ``skyquill plan``
and ``fly`` without ``--kind``, a simulated vehicle made without one, a kiosk without a show, the
console's demo."""


class UnknownKindError(LookupError):
    """A vehicle kind without a room; the message names the kinds that exist."""

    def __init__(self, name: str) -> None:
        self.name = name
        super().__init__(f"no vehicle kind {name!r}; the kinds are: {', '.join(sorted(ROOMS))}")


def kind_names() -> tuple[str, ...]:
    """The kinds that have a room, sorted."""
    return tuple(sorted(ROOMS))

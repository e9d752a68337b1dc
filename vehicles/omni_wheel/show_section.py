"""The ``omni-wheel`` room's part of a show file: its ``omni_wheel`` section (the ground writers'
vehicle, writing limits and the terrain of the floor areas: steps across world x between them)
and what a show may not ask of it (a floor area the vehicle cannot reach or write on).

``vehicles.omni_wheel.settings`` turns the section into the room's typed settings;
:func:`board_problem` asks ``vehicles.omni_wheel.check_route``. SI units, world ENU. Light:
pydantic and plain Python only (the show file loads this module; MuJoCo and numpy stay out), and
no import of the show file (``showfile.models`` imports this).
"""

from __future__ import annotations

from typing import Protocol

from pydantic import BaseModel, ConfigDict, Field, model_validator

from vehicles.omni_wheel.check_route import FloorArea, RouteError, check_route, terrain_of


class _Model(BaseModel):
    """Frozen, strict and documented like every model of a show file (``showfile.models``; held
    equal by tests/test_showfile_kinds.py)."""

    model_config = ConfigDict(frozen=True, extra="forbid", use_attribute_docstrings=True)


class StepSettings(_Model):
    """A step across world x: the floor is ``height_m`` high from ``x_m`` on."""

    x_m: float
    """World x of the step edge, in [m]."""
    height_m: float = Field(ge=0.0, le=2.0)
    """Height of the floor beyond the edge (until the next step), in [m]."""


class OmniWheelSettings(_Model):
    """The ground writers of a show: vehicle, writing limits, terrain."""

    wheel_radius_m: float = Field(default=0.066, gt=0.0, le=0.5)
    """Wheel radius in [m] (Table 1: 132 mm diameter)."""
    running_speed_mps: float = Field(default=0.25, gt=0.0, le=2.0)
    """V0: running speed and bound on every wheel's speed, in [m/s]."""
    roller_friction: float = Field(default=1.0, gt=0.0, le=2.0)
    """Friction coefficient of the rollers on the floor (rubber: 1.0; Table 1's 0.3 cannot
    climb a 50 mm step)."""
    accel_max_mps2: tuple[float, float] = (0.25, 0.15)
    """Largest planned acceleration along the vehicle's x and y, in [m/s^2]."""
    speed_max_mps: float = Field(default=0.2, gt=0.0)
    """Largest planned marker speed in [m/s] (at most ``running_speed_mps``)."""
    marker_width_m: float = Field(default=0.04, gt=0.0, le=0.5)
    """Width of the marker's line, in [m]."""
    steps: tuple[StepSettings, ...] = ()
    """Steps between the floor areas, in increasing x."""
    terrain_half_width_m: float = Field(default=20.0, gt=0.0)
    """Half width of the terrain along y, in [m]."""

    @model_validator(mode="after")
    def _consistent(self) -> OmniWheelSettings:
        if min(self.accel_max_mps2) <= 0.0:
            raise ValueError("accel_max_mps2 must be positive")
        if self.speed_max_mps > self.running_speed_mps:
            raise ValueError(
                f"speed_max_mps {self.speed_max_mps} exceeds running_speed_mps "
                f"{self.running_speed_mps}"
            )
        xs = [s.x_m for s in self.steps]
        if xs != sorted(xs) or len(set(xs)) != len(xs):
            raise ValueError("steps must be in strictly increasing x_m")
        return self


class _Show(Protocol):
    """The parts of a show (``showfile.models.Show``) the check reads."""

    @property
    def omni_wheel(self) -> OmniWheelSettings | None: ...


class _Vehicle(Protocol):
    @property
    def id(self) -> str: ...

    @property
    def home_m_enu(self) -> tuple[float, float, float]: ...


class _Board(Protocol):
    @property
    def id(self) -> str: ...

    @property
    def center_m_enu(self) -> tuple[float, float, float]: ...

    @property
    def size_m(self) -> tuple[float, float]: ...


def board_problem(show: _Show, vehicle: _Vehicle, board: _Board) -> str | None:
    """Why ``vehicle`` cannot reach its floor area ``board`` from its home or write there (behind
    a step higher than it climbs, off the terrain, straddling a step, at the wrong height, too
    far), in one line naming the area; None when it can."""
    section = show.omni_wheel or OmniWheelSettings()
    terrain = terrain_of(((s.x_m, s.height_m) for s in section.steps), section.terrain_half_width_m)
    area = FloorArea(board.id, board.center_m_enu, 0.5 * max(board.size_m))
    try:
        check_route(vehicle.home_m_enu, area, terrain)
    except RouteError as exc:
        return f"{vehicle.id} cannot write there: {exc}"
    return None

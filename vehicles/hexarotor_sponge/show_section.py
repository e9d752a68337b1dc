"""The ``hexarotor-sponge`` room's part of a show file: its ``hexarotor`` section (the Flying
Calligrapher's vehicle, pen and writing limits) and what a show may not ask of it (a wall beyond
its reach).

``vehicles.hexarotor_sponge.kind.settings_from`` turns the section into the kind's typed settings.
SI units; widths and lengths in metres. The defaults are the kind's own,
``vehicles.hexarotor_sponge.defaults``, so a show left at its defaults builds exactly the settings
of ``skyquill fly --kind hexarotor-sponge`` (tests/test_wall_kind.py). Light: pydantic and the
defaults only (the show file loads this module; CasADi and MuJoCo stay out), and no import of the
show file (``showfile.models`` imports this).
"""

from __future__ import annotations

import math
from typing import Protocol

from pydantic import BaseModel, ConfigDict, Field, model_validator

from vehicles.hexarotor_sponge import defaults


class _Model(BaseModel):
    """Frozen, strict and documented like every model of a show file (``showfile.models``; held
    equal by tests/test_showfile_kinds.py)."""

    model_config = ConfigDict(frozen=True, extra="forbid", use_attribute_docstrings=True)


class PenSettings(_Model):
    """The sponge pen's calibration (paper Fig. 4c) and spring."""

    width_coefficients_m: tuple[float, ...] = defaults.PEN_WIDTH_COEFFICIENTS_M
    """Line width [m] as a polynomial of normal force [N], lowest order first."""
    force_min_n: float = Field(default=defaults.PEN_FORCE_MIN_N, gt=0.0)
    """Lowest calibrated normal force in [N]."""
    force_max_n: float = Field(default=defaults.PEN_FORCE_MAX_N, gt=0.0)
    """Highest calibrated normal force in [N]."""
    stiffness_npm: float = Field(default=defaults.PEN_STIFFNESS_NPM, gt=0.0)
    """Spring stiffness in [N/m]."""
    preload_n: float = Field(default=defaults.PEN_PRELOAD_N, ge=0.0)
    """Spring preload in [N]."""
    default_width_m: float = Field(default=defaults.DEFAULT_WIDTH_M, gt=0.0)
    """Width in [m] where a stroke carries none and no profile applies."""
    clamp_widths: bool = defaults.CLAMP_WIDTHS
    """Clamp wanted widths outside the pen's range (counted in the plan's report) instead of
    refusing the job."""

    @model_validator(mode="after")
    def _range(self) -> PenSettings:
        if self.force_max_n <= self.force_min_n:
            raise ValueError("force_max_n must be above force_min_n")
        return self


class HexarotorKindSettings(_Model):
    """A fully-actuated hexarotor with a one-link arm writing on a wall."""

    rotor_tilt_deg: float = Field(default=math.degrees(defaults.ROTOR_TILT_RAD), ge=0.0, lt=60.0)
    """Tilt of each rotor about its arm, alternating sign, in [deg] (default: the kind's 0.52 rad,
    29.79 deg)."""
    thrust_max_n: float = Field(default=defaults.THRUST_MAX_N, gt=0.0)
    """Largest thrust of one rotor in [N]."""
    arm_length_m: float = Field(default=defaults.ARM_LENGTH_M, gt=0.0, le=2.0)
    """From the F/T sensor to the pen tip in [m]."""
    wall_friction: float = Field(default=defaults.WALL_FRICTION, ge=0.0, le=2.0)
    """Coulomb friction coefficient of pen on wall."""
    v_max_mps: float = Field(default=defaults.V_MAX_MPS, gt=0.0)
    """Largest writing speed in [m/s] (paper: 20 cm/s)."""
    a_max_mps2: float = Field(default=defaults.A_MAX_MPS2, gt=0.0)
    """Largest acceleration in [m/s^2] (paper: 20 cm/s^2)."""
    force_rate_max_nps: float = Field(default=defaults.FORCE_RATE_MAX_NPS, gt=0.0)
    """Largest change of the normal force in [N/s] (paper: 2 N/s)."""
    reach_m: float = Field(default=defaults.REACH_M, gt=0.0)
    """Farthest a stroke point may lie from the centre of the wall's writing area, in [m] (a
    writing area whose corners lie farther is refused by the show file)."""
    pen: PenSettings = PenSettings()
    """The sponge pen."""


class _Planning(Protocol):
    @property
    def margin_m(self) -> float: ...


class _Show(Protocol):
    """The parts of a show (``showfile.models.Show``) the check reads."""

    @property
    def hexarotor(self) -> HexarotorKindSettings | None: ...

    @property
    def planning(self) -> _Planning: ...


class _Vehicle(Protocol):
    @property
    def id(self) -> str: ...


class _Board(Protocol):
    @property
    def id(self) -> str: ...

    @property
    def writing_area_m(self) -> tuple[float, float]: ...


def board_problem(show: _Show, vehicle: _Vehicle, board: _Board) -> str | None:
    """Why ``vehicle`` cannot write on its wall ``board``, in one line: corners of the writing
    area (less the show's margin) beyond the section's ``reach_m``; None when it can."""
    reach_m = (show.hexarotor or HexarotorKindSettings()).reach_m
    margin_m = show.planning.margin_m
    half = [max(0.0, size / 2 - margin_m) for size in board.writing_area_m]
    corner_m = math.hypot(*half)
    if corner_m <= reach_m + defaults.REACH_SLACK_M:
        return None
    return (
        f"{vehicle.id} cannot write there: the corners of wall {board.id!r}'s writing area are "
        f"{corner_m:.3f} m from its centre, beyond the reach {reach_m:g} m (hexarotor.reach_m)"
    )

"""The brush quadrotor's settings from a show file (or the defaults a show file has).

One place decides them for the agent, the orchestrator, the kiosk preview, ``plan`` and ``fly``:
the planner options of the show's ``planning`` section and the vehicle's ``limits`` (mostly the
brush quadrotor's: each field's description names who reads it), the simulated world
(a brush reaching the show's writing height, the board's height, the control rate) and the
controller preset aiming the brush at that height, with the show's gain overrides.

Without a show, the defaults a show file has are built without importing the show file models
(pydantic: ~0.25 s of CPU, a third of a one-off ``skyquill plan``); a test keeps the two equal.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

from planner.limits import VehicleLimits
from planner.options import PlanOptions
from vehicles.quadrotor_brush.control.config import DEFAULT_CONFIG, PAPER_CONFIG, ControllerConfig
from vehicles.quadrotor_brush.control.rpt import RptGains
from vehicles.quadrotor_brush.flight_config import FlightConfig
from vehicles.quadrotor_brush.gain_names import AXES
from vehicles.quadrotor_brush.params import BrushParams, WorldParams

if TYPE_CHECKING:
    from showfile.models import Limits, PlanningSettings, Show

INK_PIXEL_M = 0.002
"""Pixel size in [m] of the ink rasters compared for a job's IoU (2 mm: cheap for 1 m glyphs)."""


@dataclass(frozen=True)
class QuadrotorSettings:
    """Everything the brush quadrotor needs to plan, fly and score a job."""

    plan: PlanOptions = field(default_factory=PlanOptions)
    """Planner options (their ``board`` is replaced by the job's surface)."""
    flight: FlightConfig = field(default_factory=FlightConfig)
    """Simulated world and controller (the world's brush reaches the board at nominal press from
    ``plan.write_height_m``, see :func:`world_params`)."""
    ink_pixel_m: float = INK_PIXEL_M
    """Pixel size in [m] of the ink rasters of the IoU."""


def world_params(
    write_height_m: float, board_height_m: float, control_rate_hz: float
) -> WorldParams:
    """The simulated world: a brush that reaches the board at nominal press from
    ``write_height_m`` above it [m], the board at ``board_height_m`` [m], ticks at
    ``control_rate_hz`` [Hz]."""
    brush = BrushParams()
    brush = replace(brush, length_m=write_height_m + brush.nominal_press_m)
    return WorldParams(brush=brush, board_height_m=board_height_m, control_rate_hz=control_rate_hz)


def controller_config(
    preset: str, write_height_m: float, overrides: Mapping[str, float] | None = None
) -> ControllerConfig:
    """The position controller of a show's ``controller.preset``, aiming the brush from
    ``write_height_m`` [m] above the board (the paper's preset aims the body), with the gains
    ``overrides`` names (``x.eps``: ``gain_names.GAIN_NAMES``) replacing the preset's."""
    config = PAPER_CONFIG
    if preset != "paper":
        config = replace(DEFAULT_CONFIG, brush_lever_m=write_height_m)
    if not overrides:
        return config
    gains = config.gains
    axes = {axis: getattr(gains, axis) for axis in AXES}
    for name, value in overrides.items():
        axis, parameter = name.split(".", 1)
        axes[axis] = replace(axes[axis], **{parameter: float(value)})
    label = f"{gains.name} with {', '.join(sorted(overrides))}"
    return replace(config, gains=RptGains(label, axes["x"], axes["y"], axes["z"]))


def quadrotor_settings(show: Show | None, vehicle_id: str | None) -> QuadrotorSettings:
    """The settings of ``vehicle_id`` in ``show`` (KeyError naming the known ids if absent), or
    with ``show`` None those of a show file that leaves every section at its default, on a
    board at height 0."""
    if show is None or vehicle_id is None:
        return _settings(PlanOptions(), 0.0, DEFAULT_CONTROL_RATE_HZ, DEFAULT_PRESET)
    vehicle = show.vehicle(vehicle_id)
    return _settings(
        plan_options(show.planning, show.vehicle_limits(vehicle_id)),
        show.board(vehicle.board).center_m_enu[2],
        show.controller.rate_hz,
        show.controller.preset,
        show.controller.overrides,
    )


def plan_options(planning: PlanningSettings, limits: Limits) -> PlanOptions:
    """Planner options of a show's ``planning`` section and a vehicle's ``limits``, on the
    planner's default board (a job's plan puts them on its surface)."""
    return PlanOptions(
        limits=VehicleLimits(
            a_max_mps2=limits.a_max_mps2,
            v_max_mps=limits.v_max_mps,
            mass_kg=limits.mass_kg,
            thrust_max_n=limits.thrust_max_n,
            body_rate_max_radps=limits.body_rate_max_radps,
        ),
        write_height_m=planning.write_height_m,
        clearance_m=planning.clearance_m,
        total_time_s=planning.total_time_s,
        split_threshold_m=planning.split_threshold_m,
        resegment=planning.resegment,
        solver=planning.solver,
        sample_rate_hz=planning.sample_rate_hz,
        pace="limits" if planning.pace == "tracking" else planning.pace,  # the agent paces
    )


DEFAULT_CONTROL_RATE_HZ = 100.0
"""A show file's default ``controller.rate_hz`` [Hz]."""
DEFAULT_PRESET = "default"
"""A show file's default ``controller.preset``."""


def _settings(
    plan: PlanOptions,
    board_height_m: float,
    control_rate_hz: float,
    preset: str,
    overrides: Mapping[str, float] | None = None,
) -> QuadrotorSettings:
    world = world_params(plan.write_height_m, board_height_m, control_rate_hz)
    controller = controller_config(preset, plan.write_height_m, overrides)
    return QuadrotorSettings(plan=plan, flight=FlightConfig(world=world, controller=controller))

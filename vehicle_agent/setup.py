"""One vehicle of a show, set up from the show file once (pure): its kind and the kind's settings,
its board, the job runner's configuration and its safety limits."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from showfile import Board, PlanningSettings, Show
from showfile.geofence import show_fence
from vehicle_agent.backends.base import Vec3
from vehicle_agent.job_runner import RunnerConfig
from vehicle_agent.preflight import PreflightLimits
from vehicle_agent.safety import DeviationLimit, SafetyLimits, WritingBounds
from vehicles.jobs import board_surface
from vehicles.kind import AutopilotWorld, JobPhases, VehicleKind
from vehicles.registry import vehicle_kind
from vehicles.surface import Surface

TELEMETRY_RATE_HZ = 20.0
"""Telemetry messages per second of wall time."""
PROGRESS_PERIOD_S = 1.0
"""Wall time in [s] between progress reports while writing."""


@dataclass(frozen=True)
class VehicleSetup:
    """Everything about one vehicle of a show, derived from the show file once."""

    show: Show
    """The validated show."""
    vehicle_id: str
    """This vehicle."""
    surface: Surface
    """Its board, wall or floor area as a writing plane (``to_surface``: world -> board metres)."""
    writing_area_m: tuple[float, float]
    """Width and height in [m] of the area glyphs are fitted to."""
    margin_m: float
    """Margin in [m] kept free inside the writing area."""
    kind: VehicleKind
    """Its vehicle kind (plans, flies in simulation, scores)."""
    settings: Any
    """The kind's settings of this vehicle (``VehicleKind.settings``)."""
    runner_config: RunnerConfig
    """The job runner's configuration."""
    time_scale: float
    """Agent seconds per wall second."""


def vehicle_setup(show: Show, vehicle_id: str, *, time_scale: float | None = None) -> VehicleSetup:
    """The setup of ``vehicle_id`` in ``show`` (KeyError naming the known ids if absent).

    ``time_scale`` (default: the show's) applies to simulated vehicles only."""
    vehicle = show.vehicle(vehicle_id)
    board = show.board(vehicle.board)
    limits = show.vehicle_limits(vehicle_id)
    planning = show.planning
    scale = float(time_scale if time_scale is not None else show.time_scale)
    if vehicle.backend != "sim":
        scale = 1.0  # an autopilot lives in real time
    kind = vehicle_kind(vehicle.kind)
    settings = kind.settings(show, vehicle.id)
    phases = kind.phases(settings)
    cruise_z_m = cruise_height_m(phases, board, vehicle.home_m_enu, planning)
    runner = RunnerConfig(
        vehicle_id=vehicle.id,
        kind=vehicle.kind,
        board_id=board.id,
        home_m_enu=vehicle.home_m_enu,
        cruise_z_m=cruise_z_m,
        v_max_mps=phases.transit_v_max_mps or limits.v_max_mps,
        a_max_mps2=phases.transit_a_max_mps2 or min(limits.a_max_mps2),
        airborne=phases.airborne,
        route=phases.route,
        transit_wait_m=phases.transit_wait_m,
        telemetry_period_s=scale / TELEMETRY_RATE_HZ,
        progress_period_s=scale * PROGRESS_PERIOD_S,
        safety=safety_limits(show, vehicle_id, cruise_z_m),
        preflight=preflight_limits(show),
    )
    return VehicleSetup(
        show=show,
        vehicle_id=vehicle.id,
        surface=board_surface(board),
        writing_area_m=board.writing_area_m,
        margin_m=planning.margin_m,
        kind=kind,
        settings=settings,
        runner_config=runner,
        time_scale=scale,
    )


def cruise_height_m(
    phases: JobPhases, board: Board, home_m_enu: Vec3, planning: PlanningSettings
) -> float:
    """World z in [m] of the vehicle's pen-up moves (see :class:`vehicles.kind.JobPhases`)."""
    centre_z_m = board.center_m_enu[2]
    if phases.cruise == "above_surface":
        return centre_z_m + planning.write_height_m + planning.clearance_m
    if phases.cruise == "above_area":
        return centre_z_m + 0.5 * board.writing_area_m[1] + planning.clearance_m
    return max(home_m_enu[2], centre_z_m)


def preflight_limits(show: Show) -> PreflightLimits:
    """The bounds of the vehicle's preflight: the show's ``preflight`` section and its battery
    reserve."""
    p = show.preflight
    return PreflightLimits(
        link_age_max_s=p.link_age_max_s,
        link_loss_max_fraction=p.link_loss_max_fraction,
        mocap_age_max_s=p.mocap_age_max_s,
        battery_reserve_fraction=show.battery.reserve_fraction,
        clock_offset_max_s=p.clock_offset_max_s,
    )


def safety_limits(show: Show, vehicle_id: str, cruise_z_m: float) -> SafetyLimits:
    """The show's ``safety`` section for one vehicle, with its geofence (its board, its home and
    the transit between them, up to ``cruise_z_m`` plus the ceiling margin)."""
    s = show.safety
    fence = show_fence(show, vehicle_id, cruise_z_m)
    return SafetyLimits(
        deviation=DeviationLimit(s.deviation_bound_m, s.deviation_window_s),
        fence=fence,
        writing=WritingBounds(s.rmse_pen_down_max_m, s.iou_min),
        abort_policy=s.abort_policy,
        abort_hold_s=s.abort_hold_s,
        abort_backoff_s=s.abort_backoff_s,
        fence_hold_s=s.fence_hold_s,
        settle_tolerance_m=s.settle_tolerance_m,
        settle_hold_s=s.settle_hold_s,
        settle_timeout_s=s.settle_timeout_s,
        settle_attempts=s.settle_attempts,
    )


def on_board(setup: VehicleSetup) -> Callable[[Vec3], bool]:
    """Whether a point lies over (a wall: in front of) this vehicle's board, within its edges."""
    board = setup.show.board(setup.show.vehicle(setup.vehicle_id).board)
    half_x_m, half_y_m = (0.5 * float(size) for size in board.size_m)
    surface = setup.surface
    ox, oy, oz = surface.origin_m_enu
    (xx, xy, xz), (yx, yy, yz) = surface.x_axis_enu, surface.y_axis_enu

    def inside(point_m_enu: Vec3) -> bool:
        # in floats, not numpy: asked at every control tick of a simulated vehicle (~3 us
        # against ~200 us through Surface.to_surface on a (1, 3) array)
        dx, dy, dz = point_m_enu[0] - ox, point_m_enu[1] - oy, point_m_enu[2] - oz
        x_m = dx * xx + dy * xy + dz * xz
        y_m = dx * yx + dy * yy + dz * yz
        return abs(x_m) <= half_x_m and abs(y_m) <= half_y_m

    return inside


def autopilot_world(setup: VehicleSetup) -> AutopilotWorld:
    """What this vehicle flown behind an autopilot takes from its kind's simulated world (its
    pen from its pose, the mocap; ``VehicleKind.autopilot_world``, for the MAVLink backend);
    ValueError for a kind that flies in the sim only."""
    world = setup.kind.autopilot_world(setup.settings)
    if world is None:
        raise ValueError(
            f"vehicle {setup.vehicle_id}: a {setup.kind.name} cannot fly behind an autopilot "
            "(backend: mavlink) yet; use backend: sim"
        )
    return world

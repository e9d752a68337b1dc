"""The planner's view of a show (pure): board frames, limits, plan options, glyph layout.

Every service that plans a job on a show's board (vehicle agent, orchestrator estimates, kiosk
preview) builds its :class:`planner.pipeline.PlanOptions` here, so they all plan alike. Not
re-exported by ``showfile/__init__`` so that readers of show files need not import the planner.
"""

from __future__ import annotations

from planner.board import BoardFrame
from planner.glyphs import Glyph, fit_to_area
from planner.limits import VehicleLimits
from planner.options import PlanOptions
from showfile.models import Board, Limits, PlanningSettings, Show


def board_frame(board: Board) -> BoardFrame:
    """The planner's frame of a board (its centre and yaw)."""
    return BoardFrame(center_m_enu=board.center_m_enu, yaw_rad=board.yaw_rad)


def vehicle_limits(limits: Limits) -> VehicleLimits:
    """The planner's limits from a show's limits."""
    return VehicleLimits(
        a_max_mps2=limits.a_max_mps2,
        v_max_mps=limits.v_max_mps,
        mass_kg=limits.mass_kg,
        thrust_max_n=limits.thrust_max_n,
        body_rate_max_radps=limits.body_rate_max_radps,
    )


def plan_options(
    planning: PlanningSettings, limits: Limits, board: BoardFrame | None = None
) -> PlanOptions:
    """Planner options of the show's planning settings and ``limits``, on ``board`` (default:
    a board centred on the origin)."""
    return PlanOptions(
        limits=vehicle_limits(limits),
        board=board if board is not None else BoardFrame(center_m_enu=(0.0, 0.0, 0.0)),
        write_height_m=planning.write_height_m,
        clearance_m=planning.clearance_m,
        total_time_s=planning.total_time_s,
        split_threshold_m=planning.split_threshold_m,
        resegment=planning.resegment,
        solver=planning.solver,
        sample_rate_hz=planning.sample_rate_hz,
        pace=planning.pace,
    )


def vehicle_plan_options(show: Show, vehicle_id: str) -> PlanOptions:
    """Planner options of one vehicle: its limits, on its board (KeyError if unknown)."""
    board = show.board(show.vehicle(vehicle_id).board)
    return plan_options(show.planning, show.vehicle_limits(vehicle_id), board_frame(board))


def fit_to_board(glyph: Glyph, board: Board, planning: PlanningSettings) -> Glyph:
    """``glyph`` scaled and centred into the board's writing area, keeping the show's margin
    (raises PlannerError if it cannot fit)."""
    width_m, height_m = board.writing_area_m
    return fit_to_area(glyph, width_m=width_m, height_m=height_m, margin_m=planning.margin_m)

"""The one job-planning function: glyph -> laid out on the vehicle's surface -> the kind's plan.

Used by the agent, the orchestrator's estimates, the kiosk preview, ``skyquill plan`` and
``skyquill fly``, so every one of them plans a job the way the vehicle will write it.
:func:`plan_job` plans for a vehicle of a show; :func:`plan_glyph` is the same pipeline for a
kind, its settings and a writing area given directly (the kiosk's preview area, the CLI without a
show file).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from planner.glyphs import Glyph, fit_to_area
from vehicles.kind import StrokeInput, VehicleKind, WritingPlan
from vehicles.registry import vehicle_kind
from vehicles.surface import Surface

if TYPE_CHECKING:
    from showfile.models import Board, Show


@dataclass(frozen=True)
class JobPlan:
    """A planned job: the glyph as laid out and the kind's plan of it."""

    glyph: Glyph
    """The glyph laid out on the writing area (surface metres, centred)."""
    plan: WritingPlan
    """The kind's plan (reference, feasibility)."""


def board_surface(board: Board) -> Surface:
    """The writing surface of a show's board."""
    return Surface.of(board.orientation, board.center_m_enu, board.yaw_rad)


def lay_out(glyph: Glyph, writing_area_m: tuple[float, float], margin_m: float) -> Glyph:
    """``glyph`` scaled and centred into the writing area (width, height in [m]) keeping
    ``margin_m`` free, whatever its units: a job never leaves its area (raises PlannerError)."""
    width_m, height_m = writing_area_m
    return fit_to_area(glyph, width_m=width_m, height_m=height_m, margin_m=margin_m)


def plan_glyph(
    kind: VehicleKind,
    settings: Any,
    surface: Surface,
    glyph: Glyph,
    writing_area_m: tuple[float, float],
    margin_m: float,
) -> JobPlan:
    """Lay ``glyph`` out on the writing area and plan it with ``kind`` (raises PlannerError)."""
    fitted = lay_out(glyph, writing_area_m, margin_m)
    widths = fitted.widths_m or (None,) * len(fitted.strokes)
    strokes = tuple(
        StrokeInput(np.asarray(s, dtype=np.float64), width_m=w)
        for s, w in zip(fitted.strokes, widths, strict=True)
    )
    return JobPlan(fitted, kind.plan(strokes, surface, settings))


def plan_job(show: Show, vehicle_id: str, glyph: Glyph) -> JobPlan:
    """Plan ``glyph`` for vehicle ``vehicle_id`` of ``show`` on its board: its kind, its
    settings (limits, planning section, controller), the board's writing area and the show's
    margin (KeyError naming the known ids if absent; PlannerError if it cannot be written)."""
    vehicle = show.vehicle(vehicle_id)
    board = show.board(vehicle.board)
    kind = vehicle_kind(vehicle.kind)
    return plan_glyph(
        kind,
        kind.settings(show, vehicle_id),
        board_surface(board),
        glyph,
        board.writing_area_m,
        show.planning.margin_m,
    )

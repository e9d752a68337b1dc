"""The one job-planning function: glyph -> laid out on the vehicle's surface -> the kind's plan.

Used by the agent, the orchestrator's estimates, the kiosk preview, ``skyquill plan`` and
``skyquill fly``, so every one of them plans a job the way the vehicle will write it.
:func:`plan_job` plans for a vehicle of a show (:func:`job_setup`: what it plans with);
:func:`plan_glyph` is the same pipeline for a kind, its settings and a writing area given
directly (the CLI without a show file). Where a glyph is planned once per kind of a show (the
orchestrator's ETAs and refusals, the kiosk's preview), :func:`kind_writers` says which vehicle
stands for each kind.
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


@dataclass(frozen=True)
class JobSetup:
    """What a vehicle of a show plans a job with, besides the glyph (:func:`plan_glyph`'s
    other arguments)."""

    kind: VehicleKind
    """The vehicle's kind."""
    settings: Any
    """The kind's settings of the vehicle (``VehicleKind.settings``)."""
    surface: Surface
    """The vehicle's board."""
    writing_area_m: tuple[float, float]
    """Width and height in [m] of the board's writing area."""
    margin_m: float
    """Free border in [m] kept inside the writing area (the show's)."""

    def plan(self, glyph: Glyph) -> JobPlan:
        """Lay ``glyph`` out and plan it (raises PlannerError if it cannot be written)."""
        return plan_glyph(
            self.kind, self.settings, self.surface, glyph, self.writing_area_m, self.margin_m
        )


def job_setup(show: Show, vehicle_id: str) -> JobSetup:
    """How vehicle ``vehicle_id`` of ``show`` plans a job: its kind, its settings (limits,
    planning section, controller), its board's surface and writing area and the show's margin
    (KeyError naming the known ids if absent)."""
    vehicle = show.vehicle(vehicle_id)
    board = show.board(vehicle.board)
    kind = vehicle_kind(vehicle.kind)
    return JobSetup(
        kind,
        kind.settings(show, vehicle_id),
        board_surface(board),
        board.writing_area_m,
        show.planning.margin_m,
    )


def plan_job(show: Show, vehicle_id: str, glyph: Glyph) -> JobPlan:
    """Plan ``glyph`` for vehicle ``vehicle_id`` of ``show`` on its board (:func:`job_setup`;
    KeyError naming the known ids if absent; PlannerError if it cannot be written)."""
    return job_setup(show, vehicle_id).plan(glyph)


def kind_writers(show: Show) -> dict[str, str]:
    """Kind -> the vehicle that stands for it where a glyph is planned once per kind: the first
    vehicle of each kind in board order (the boards as listed, a board's vehicles as listed), so
    the kinds come in the order of their first board."""
    writers: dict[str, str] = {}
    for board in show.boards:
        for vehicle in show.vehicles:
            if vehicle.board == board.id:
                writers.setdefault(vehicle.kind, vehicle.id)
    return writers

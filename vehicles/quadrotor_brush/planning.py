"""The brush quadrotor's plan of strokes on its surface: the Airshow planner
(:func:`planner.pipeline.plan_strokes`) on the board of a horizontal surface.

Apart from the kind (:mod:`vehicles.quadrotor_brush.kind`), whose settings hold the simulated
world and the controller too: ``skyquill plan`` plans here, as the kind does, without loading
them (nor the kinds' interface, :mod:`vehicles.kind`). The planner itself is imported on the
first plan: a live agent that only flies never loads it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

from planner.board import BoardFrame

if TYPE_CHECKING:
    from planner.bspline import FloatArray
    from planner.options import PlanOptions
    from planner.trajectory import PlannedTrajectory
    from vehicles.surface import Surface


def board_of(surface: Surface) -> BoardFrame:
    """The planner's frame of a horizontal surface."""
    x, y, _ = surface.x_axis_enu
    return BoardFrame(center_m_enu=surface.origin_m_enu, yaw_rad=math.atan2(y, x))


def plan_on_surface(
    strokes_xy_m: Sequence[FloatArray], surface: Surface, options: PlanOptions
) -> PlannedTrajectory:
    """The brush writing point's trajectory writing ``strokes_xy_m`` ((n, 2) points each, in
    surface metres) on ``surface`` with ``options`` (their board replaced by the surface's;
    raises PlannerError)."""
    from planner.pipeline import plan_strokes

    return plan_strokes(list(strokes_xy_m), replace(options, board=board_of(surface)))

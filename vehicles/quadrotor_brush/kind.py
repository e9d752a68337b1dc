"""The brush quadrotor over a horizontal board (Airshow, Phang et al. 2015) as a vehicle kind.

Plans with the Airshow planner (:mod:`vehicles.quadrotor_brush.planning`), flies in its own world
(:mod:`vehicles.quadrotor_brush.world`) under its RPT controller
(:mod:`vehicles.quadrotor_brush.control`), scores tracking at the writing point and the ink IoU
(:mod:`vehicles.quadrotor_brush.metrics`) and draws ``report.png``
(:mod:`vehicles.quadrotor_brush.report`, imported only when a report is drawn). The planner, the
batch flight and the metrics are imported where they are used: a live agent that only flies
loads none of them (nor scipy); nor does a plan load the closed loop, the live vehicle or the
autopilot's pen.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from planner.samples import TrajectorySamples
from vehicles.kind import (
    AutopilotWorld,
    FlownWriting,
    JobPhases,
    StrokeInput,
    WritingPlan,
    WritingScore,
)
from vehicles.quadrotor_brush import KIND_NAME
from vehicles.quadrotor_brush.planning import board_of, plan_on_surface
from vehicles.quadrotor_brush.settings import QuadrotorSettings, quadrotor_settings
from vehicles.surface import Orientation, Surface, Vec3

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from showfile.models import Show
    from vehicles.quadrotor_brush.loop import QuadrotorFleet, SimulatedQuadrotor


class QuadrotorBrush:
    """The ``quadrotor-brush`` kind (see :class:`vehicles.kind.VehicleKind`)."""

    name = KIND_NAME
    orientation: Orientation = "horizontal"

    def phases(self, settings: QuadrotorSettings) -> JobPhases:
        """Takes off, flies above its board at the show's write height plus clearance, lands."""
        return JobPhases(airborne=True, cruise="above_surface")

    def width_range_m(self, settings: QuadrotorSettings) -> None:
        """None: the brush's width follows its height, not the visitor's line."""
        return None

    def autopilot_world(self, settings: QuadrotorSettings) -> AutopilotWorld:
        """The brush over the board and the mocap of its simulated world (MAVLink backend)."""
        from vehicles.quadrotor_brush.autopilot_pen import autopilot_world

        return autopilot_world(settings.flight.world)

    def settings(self, show: Show | None, vehicle_id: str | None) -> QuadrotorSettings:
        """Settings of ``vehicle_id`` in ``show``, or a default show's with ``show`` None."""
        return quadrotor_settings(show, vehicle_id)

    def plan(
        self, strokes: Sequence[StrokeInput], surface: Surface, settings: QuadrotorSettings
    ) -> WritingPlan:
        """The Airshow planner's reference of the brush writing point (raises PlannerError)."""
        trajectory = plan_on_surface([s.xy_m for s in strokes], surface, settings.plan)
        return WritingPlan(
            samples=trajectory.sample(settings.plan.sample_rate_hz),
            strokes=tuple(strokes),
            surface=surface,
            feasibility=trajectory.feasibility.to_json_dict(),
            turning_points_m=trajectory.turning_points_board_m,
            detail=trajectory,
        )

    def command_reference(
        self, plan: WritingPlan, settings: QuadrotorSettings
    ) -> TrajectorySamples:
        """The body reference that puts the brush tip on the plan, with the acceleration
        feed-forward led by the inner loop's lag: the preprocessing the batch flight applies
        (:func:`vehicles.quadrotor_brush.control.controller.body_reference`), so the live agent
        and a batch flight fly the same."""
        from vehicles.quadrotor_brush.control.controller import body_reference

        s = plan.samples
        dt_s = float(np.mean(np.diff(s.t_s)))
        p, v, a = body_reference(
            settings.flight.controller,
            s.position_m_enu,
            s.velocity_mps_enu,
            s.acceleration_mps2_enu,
            dt_s,
        )
        return TrajectorySamples(s.t_s, p, v, a, s.pen_down)

    def fly(self, plan: WritingPlan, settings: QuadrotorSettings, *, seed: int = 0) -> FlownWriting:
        """Fly ``plan`` in the simulated world to its end (one vehicle, batch)."""
        from vehicles.quadrotor_brush.flight import fly
        from vehicles.quadrotor_brush.trace import flown_of

        return flown_of(fly([plan.samples], settings.flight, seed=seed))

    def score(
        self, plan: WritingPlan, flown: FlownWriting, settings: QuadrotorSettings
    ) -> WritingScore:
        """Writing-point errors and ink IoU (Phang 2015 Fig. 12, Guo 2024 section VII)."""
        from vehicles.quadrotor_brush.metrics import flight_metrics, writing_point_error

        brush = settings.flight.world.brush
        m = flight_metrics(flown, brush, plan.samples, pixel_m=settings.ink_pixel_m)
        measured = {k: v for k, v in m.to_json_dict().items() if v is not None}
        return WritingScore(
            rmse_pen_down_m=m.rmse_pen_down_m,
            rmse_m=m.rmse_m,
            max_error_m=m.max_error_m,
            iou=m.iou if math.isfinite(m.iou) else None,
            extra={k: v for k, v in measured.items() if k not in _SCORE_FIELDS},
            error_m=np.linalg.norm(writing_point_error(flown, brush), axis=1),
        )

    def report(
        self,
        plan: WritingPlan,
        flown: FlownWriting,
        settings: QuadrotorSettings,
        title: str,
    ) -> Figure:
        """The report figure: tracking against time, paths on the board, ink against target."""
        from vehicles.quadrotor_brush.metrics import flight_metrics, ink_result
        from vehicles.quadrotor_brush.report import build_report

        brush = settings.flight.world.brush
        ink = ink_result(flown, brush, plan.samples, pixel_m=settings.ink_pixel_m)
        scores = flight_metrics(flown, brush, plan.samples, ink=ink)
        board = board_of(plan.surface)
        strokes_xy = [board.to_world(np.asarray(s.xy_m))[:, :2] for s in plan.strokes]
        return build_report(
            flown, plan.samples, brush, scores, ink, input_strokes_xy_m=strokes_xy, title=title
        )

    def simulated_vehicle(
        self, start_m_enu: Vec3, settings: QuadrotorSettings, *, seed: int = 0
    ) -> SimulatedQuadrotor:
        """One live simulated quadrotor hovering at ``start_m_enu`` (the agent's sim backend
        creates one per flight, at take-off)."""
        from vehicles.quadrotor_brush.loop import SimulatedQuadrotor

        flight = settings.flight
        return SimulatedQuadrotor(start_m_enu, flight.world, flight.controller, seed=seed)

    def simulated_fleet(self, settings: QuadrotorSettings) -> QuadrotorFleet:
        """Live simulated quadrotors of these settings stepped together (a fleet host)."""
        from vehicles.quadrotor_brush.loop import QuadrotorFleet

        return QuadrotorFleet(settings.flight.world, settings.flight.controller)


_SCORE_FIELDS = ("rmse_pen_down_m", "rmse_m", "max_error_m", "iou")

KIND = QuadrotorBrush()
"""The kind, as the registry (:mod:`vehicles`) hands it out."""

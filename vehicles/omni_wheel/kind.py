"""The omnidirectional step-climbing ground writer (Chugo et al.) as a vehicle kind.

Plans with the stroke pipeline in the floor plane (:mod:`vehicles.omni_wheel.writing`), drives in
MuJoCo (:mod:`vehicles.omni_wheel.sim`) with the proposed wheel control
(:mod:`vehicles.omni_wheel.wheel_control`), scores the marker's tracking and the ink IoU, and
draws ``report.png`` (:mod:`vehicles.omni_wheel.report`, imported only when a report is drawn).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from planner.samples import TrajectorySamples
from vehicles.kind import FlownWriting, StrokeInput, WritingPlan, WritingScore
from vehicles.omni_wheel.live import OmniLiveVehicle
from vehicles.omni_wheel.writing import (
    DEFAULT_SETTINGS,
    OmniSettings,
    drive_plan,
    plan_floor,
    score_floor,
)
from vehicles.surface import Orientation, Surface, Vec3

if TYPE_CHECKING:
    from matplotlib.figure import Figure


class OmniWheel:
    """The ``omni-wheel`` kind (see :class:`vehicles.kind.VehicleKind`)."""

    name = "omni-wheel"
    orientation: Orientation = "floor"

    def settings(self, show: Any, vehicle_id: str | None) -> OmniSettings:
        """Settings of ``vehicle_id`` in ``show``; until the show file carries the kind's
        section (``showfile/kind_omni.py``, not wired yet) every vehicle gets the defaults."""
        return DEFAULT_SETTINGS

    def plan(
        self, strokes: Sequence[StrokeInput], surface: Surface, settings: OmniSettings
    ) -> WritingPlan:
        """The marker's reference on the floor area (raises PlannerError)."""
        return plan_floor(strokes, surface, settings)

    def command_reference(self, plan: WritingPlan, settings: OmniSettings) -> TrajectorySamples:
        """The marker is the vehicle's reference point: the plan itself."""
        return plan.samples

    def fly(self, plan: WritingPlan, settings: OmniSettings, *, seed: int = 0) -> FlownWriting:
        """Drive ``plan`` in MuJoCo to its end (one vehicle, batch)."""
        return drive_plan(plan, settings, seed=seed)

    def score(self, plan: WritingPlan, flown: FlownWriting, settings: OmniSettings) -> WritingScore:
        """Marker errors and ink IoU at the marker's width."""
        return score_floor(plan, flown, settings.marker_width_m)

    def report(
        self, plan: WritingPlan, flown: FlownWriting, settings: OmniSettings, title: str
    ) -> Figure:
        """Floor, tracking error and wheel slip."""
        from vehicles.omni_wheel.report import build_report

        return build_report(plan, flown, self.score(plan, flown, settings), title)

    def simulated_vehicle(
        self, start_m_enu: Vec3, settings: OmniSettings, *, seed: int = 0
    ) -> OmniLiveVehicle:
        """One live ground writer at rest at ``start_m_enu`` (motors off until enabled)."""
        return OmniLiveVehicle(start_m_enu, settings, seed=seed)


KIND = OmniWheel()
"""The kind, as the registry (:mod:`vehicles`) hands it out."""

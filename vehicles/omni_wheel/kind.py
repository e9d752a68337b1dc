"""The omnidirectional step-climbing ground writer (Chugo et al.) as a vehicle kind.

Plans with the stroke pipeline in the floor plane (:mod:`vehicles.omni_wheel.floor_plan`), drives
in MuJoCo (:mod:`vehicles.omni_wheel.writing` on :mod:`vehicles.omni_wheel.sim`) with the proposed
wheel control (:mod:`vehicles.omni_wheel.wheel_control`), scores the marker's tracking and the ink
IoU, and draws ``report.png`` (:mod:`vehicles.omni_wheel.report`). MuJoCo, the scoring and the
report are imported only in the methods that use them: settings, phases and a plan (a kiosk
preview, an orchestrator's estimate) load the planner alone.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from planner.samples import TrajectorySamples
from vehicles.kind import FlownWriting, JobPhases, StrokeInput, WritingPlan, WritingScore
from vehicles.omni_wheel.floor_plan import DEFAULT_SETTINGS, OmniSettings, plan_floor
from vehicles.omni_wheel.settings import omni_settings
from vehicles.surface import Orientation, Surface, Vec3

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from vehicles.omni_wheel.live import OmniLiveVehicle

TRANSIT_WAIT_M = 0.05
"""The pen-up reference waits for the writer while it is this far behind in [m] (it stalls on a
step's face while it climbs)."""


class OmniWheel:
    """The ``omni-wheel`` kind (see :class:`vehicles.kind.VehicleKind`)."""

    name = "omni-wheel"
    orientation: Orientation = "floor"

    def settings(self, show: Any, vehicle_id: str | None) -> OmniSettings:
        """Settings of the ground writers of ``show`` (its ``omni_wheel`` section: vehicle,
        limits, terrain); the defaults without a show or a section."""
        section = None if show is None else show.omni_wheel
        return DEFAULT_SETTINGS if section is None else omni_settings(section)

    def autopilot_world(self, settings: Any) -> None:
        """No autopilot flies this kind yet: the sim backend only."""
        return None

    def width_range_m(self, settings: OmniSettings) -> None:
        """None: the marker draws one width."""
        return None

    def phases(self, settings: OmniSettings) -> JobPhases:
        """Rests on the floor; drives to its area with the marker up, sideways first, then
        along x over the steps, within its planned speed and acceleration."""
        return JobPhases(
            airborne=False,
            cruise="floor",
            transit_v_max_mps=settings.speed_max_mps,
            transit_a_max_mps2=min(settings.accel_max_mps2),
            route="sideways_first",
            transit_wait_m=TRANSIT_WAIT_M,
        )

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
        from vehicles.omni_wheel.writing import drive_plan

        return drive_plan(plan, settings, seed=seed)

    def score(self, plan: WritingPlan, flown: FlownWriting, settings: OmniSettings) -> WritingScore:
        """Marker errors and ink IoU at the marker's width."""
        from vehicles.omni_wheel.writing import score_floor

        return score_floor(plan, flown, settings.marker_width_m)

    def report(
        self, plan: WritingPlan, flown: FlownWriting, settings: OmniSettings, title: str
    ) -> Figure:
        """Floor, tracking error and wheel slip."""
        from vehicles.omni_wheel.report import build_report

        return build_report(plan, flown, self.score(plan, flown, settings), title)

    def simulated_fleet(self, settings: Any) -> None:
        """None: a fleet host steps each vehicle alone (no batched world yet)."""
        return None

    def simulated_vehicle(
        self, start_m_enu: Vec3, settings: OmniSettings, *, seed: int = 0
    ) -> OmniLiveVehicle:
        """One live ground writer at rest at ``start_m_enu`` (motors off until enabled)."""
        from vehicles.omni_wheel.live import OmniLiveVehicle

        return OmniLiveVehicle(start_m_enu, settings, seed=seed)


KIND = OmniWheel()
"""The kind, as the registry (:mod:`vehicles`) hands it out."""

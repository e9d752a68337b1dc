"""The hexarotor sponge writer behind the vehicle-kind interface (``vehicles.kind``).

Settings, phases, widths and a plan (CasADi + IPOPT) load no MuJoCo: the simulated flight, the
live vehicle, the metrics and the report are imported in the methods that use them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
from numpy.typing import NDArray

from planner.samples import TrajectorySamples
from vehicles.hexarotor_sponge.fly_settings import FlySettings
from vehicles.hexarotor_sponge.limits import Limits
from vehicles.hexarotor_sponge.params import HexarotorParams
from vehicles.hexarotor_sponge.pen import PenCurve
from vehicles.hexarotor_sponge.plan import PlanSettings, plan_writing
from vehicles.hexarotor_sponge.show_section import HexarotorKindSettings
from vehicles.hexarotor_sponge.widths import default_width_profile, with_profile_knots
from vehicles.kind import FlownWriting, JobPhases, StrokeInput, WritingPlan, WritingScore
from vehicles.surface import Orientation, Surface, Vec3

if TYPE_CHECKING:
    from vehicles.hexarotor_sponge.live import WallVehicle

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class WallSettings:
    """Everything the kind needs: planning, the simulated flight, and the wall of a live
    vehicle."""

    plan: PlanSettings = field(default_factory=PlanSettings)
    """Planner limits and the pen."""
    fly: FlySettings = field(default_factory=FlySettings)
    """Simulated world and controller."""
    surface: Surface | None = None
    """The wall of a live simulated vehicle (None: no live vehicle can be made)."""


def settings_from(model: HexarotorKindSettings, surface: Surface | None = None) -> WallSettings:
    """The kind's typed settings from a show file's ``hexarotor-sponge`` section."""
    pen = model.pen
    params = HexarotorParams(
        rotor_tilt_rad=math.radians(model.rotor_tilt_deg),
        thrust_max_n=model.thrust_max_n,
        arm_length_m=model.arm_length_m,
        wall_friction=model.wall_friction,
        pen_stiffness_npm=pen.stiffness_npm,
        pen_preload_n=pen.preload_n,
        pen=PenCurve(pen.width_coefficients_m, pen.force_min_n, pen.force_max_n),
    )
    limits = Limits(
        v_max_mps=model.v_max_mps,
        a_max_mps2=model.a_max_mps2,
        force_rate_max_nps=model.force_rate_max_nps,
    )
    return WallSettings(
        plan=PlanSettings(
            params=params,
            limits=limits,
            default_width_m=pen.default_width_m,
            clamp_widths=pen.clamp_widths,
            reach_m=model.reach_m,
        ),
        fly=FlySettings(params=params),
        surface=surface,
    )


class _Show(Protocol):
    """The parts of a show file (``showfile.models.Show``) the kind reads."""

    @property
    def hexarotor(self) -> HexarotorKindSettings | None: ...

    def vehicle(self, vehicle_id: str) -> Any: ...

    def board(self, board_id: str) -> Any: ...


def with_default_widths(
    strokes: Sequence[StrokeInput], settings: WallSettings
) -> list[StrokeInput]:
    """Strokes with no widths get the typed-text width profile."""
    pen = settings.plan.params.pen
    out = []
    for s in strokes:
        if s.width_m is not None:
            out.append(s)
            continue
        xy = with_profile_knots(s.xy_m)
        out.append(StrokeInput(xy, default_width_profile(xy, pen)))
    return out


class HexarotorSpongeKind:
    """The Flying Calligrapher: a fully-actuated hexarotor writing on a wall with a sponge."""

    name = "hexarotor-sponge"
    """Kind name in show files."""
    orientation: Orientation = "vertical"
    """It writes on walls."""

    def settings(self, show: _Show | None, vehicle_id: str | None) -> WallSettings:
        """Settings of ``vehicle_id`` in ``show``: the show's ``hexarotor`` section (defaults
        without one) and the vehicle's wall; the defaults and no wall without a show."""
        if show is None:
            return WallSettings()
        surface = None
        if vehicle_id is not None:
            board = show.board(show.vehicle(vehicle_id).board)
            surface = Surface.of(board.orientation, board.center_m_enu, board.yaw_rad)
        return settings_from(show.hexarotor or HexarotorKindSettings(), surface)

    def autopilot_world(self, settings: Any) -> None:
        """No autopilot flies this kind yet: the sim backend only."""
        return None

    def width_range_m(self, settings: Any) -> tuple[float, float]:
        """The sponge's lines at its lowest and highest calibrated force."""
        pen = _settings(settings).plan.params.pen
        return pen.width_min_m, pen.width_max_m

    def phases(self, settings: Any) -> JobPhases:
        """Takes off, flies level with the top of its writing area, then down to the first
        free-flight waypoint in front of the wall at its writing limits; the plan makes and
        leaves contact."""
        limits = _settings(settings).plan.limits
        return JobPhases(
            airborne=True,
            cruise="above_area",
            transit_v_max_mps=limits.v_max_mps,
            transit_a_max_mps2=limits.a_max_mps2,
        )

    def plan(self, strokes: Sequence[StrokeInput], surface: Surface, settings: Any) -> WritingPlan:
        """Contact-aware motion-force plan (strokes without widths get the default profile)."""
        s = _settings(settings)
        return plan_writing(with_default_widths(strokes, s), surface, s.plan)

    def command_reference(self, plan: WritingPlan, settings: Any) -> TrajectorySamples:
        """The controller tracks the writing point itself."""
        return plan.samples

    def fly(self, plan: WritingPlan, settings: Any, *, seed: int = 0) -> FlownWriting:
        """Fly the plan in the MuJoCo world under the hybrid controller."""
        from vehicles.hexarotor_sponge.flight import fly_plan

        return fly_plan(plan, _settings(settings).fly, seed=seed)

    def score(self, plan: WritingPlan, flown: FlownWriting, settings: Any = None) -> WritingScore:
        """Table I's metrics (``rmse_ee_m``, ``rmse_base_m``, ``force_rmse_n``, IoU); a live
        run, sampled at its own ticks, is compared with the plan at those ticks."""
        from vehicles.hexarotor_sponge.metrics import score_writing

        s = _settings(settings)
        plan, flown = aligned(plan, flown)
        return score_writing(plan, flown, s.fly.params, s.plan.default_width_m)

    def report(self, plan: WritingPlan, flown: FlownWriting, settings: Any, title: str) -> Any:
        """Images, tip error, force and width against time."""
        from vehicles.hexarotor_sponge.report import report_figure

        s = _settings(settings)
        score = self.score(plan, flown, s)
        return report_figure(plan, flown, score, title, s.plan.default_width_m)

    def simulated_fleet(self, settings: Any) -> None:
        """None: a fleet host steps each vehicle alone (no batched world yet)."""
        return None

    def simulated_vehicle(self, start_m_enu: Vec3, settings: Any, *, seed: int = 0) -> WallVehicle:
        """A live vehicle, tip at ``start_m_enu``, hovering in front of the settings' wall."""
        from vehicles.hexarotor_sponge.live import WallVehicle

        s = _settings(settings)
        if s.surface is None:
            raise ValueError("hexarotor-sponge: a live vehicle needs settings.surface (its wall)")
        start = np.asarray(start_m_enu, dtype=np.float64)
        return WallVehicle(
            start, s.surface, s.fly, default_width_m=s.plan.default_width_m, seed=seed
        )


def aligned(plan: WritingPlan, flown: FlownWriting) -> tuple[WritingPlan, FlownWriting]:
    """``plan`` at the ticks of ``flown`` (a live run's own clock), and ``flown`` without a base
    when its base is its writing point (a live vehicle reports its tip only); unchanged when
    they share their ticks (a batch flight)."""
    t = flown.t_s
    ref = plan.samples
    if t.shape == ref.t_s.shape and np.allclose(t, ref.t_s):
        return plan, flown
    t = np.clip(t, 0.0, ref.duration_s)

    def at(values: FloatArray) -> FloatArray:
        if values.ndim == 1:
            return np.interp(t, ref.t_s, values)
        return np.column_stack(
            [np.interp(t, ref.t_s, values[:, i]) for i in range(values.shape[1])]
        )

    index = np.clip(np.searchsorted(ref.t_s, t, side="right") - 1, 0, ref.t_s.size - 1)
    samples = TrajectorySamples(
        t_s=flown.t_s,
        position_m_enu=at(ref.position_m_enu),
        velocity_mps_enu=at(ref.velocity_mps_enu),
        acceleration_mps2_enu=at(ref.acceleration_mps2_enu),
        pen_down=ref.pen_down[index],
    )
    plan = replace(
        plan,
        samples=samples,
        force_n=None if plan.force_n is None else at(plan.force_n),
        width_m=None if plan.width_m is None else at(plan.width_m),
    )
    base = flown.base_m_enu
    if base is not None and np.allclose(base, flown.writing_point_m_enu):
        flown = replace(flown, base_m_enu=None)
    return plan, flown


def _settings(settings: Any) -> WallSettings:
    if settings is None:
        return WallSettings()
    if not isinstance(settings, WallSettings):
        raise TypeError(f"hexarotor-sponge expects WallSettings, got {type(settings).__name__}")
    return settings


KIND = HexarotorSpongeKind()
"""The kind as the registry sees it."""

"""The hexarotor kind's metrics and interface."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from planner.samples import TrajectorySamples
from vehicles.hexarotor_sponge.flight import fly_plan
from vehicles.hexarotor_sponge.fly_settings import FlySettings
from vehicles.hexarotor_sponge.kind import KIND, WallSettings, with_default_widths
from vehicles.hexarotor_sponge.metrics import reference_base_m_enu
from vehicles.hexarotor_sponge.params import HexarotorParams
from vehicles.kind import FlownWriting, LiveReference, StrokeInput, WritingPlan
from vehicles.surface import Surface

SHOWS = Path(__file__).resolve().parent.parent / "shows"
SURFACE = Surface.of("vertical", (0.0, 3.0, 2.0), 0.0)
WIDTH_M = 10e-3


def _line_plan() -> WritingPlan:
    """A 20 cm horizontal line of 10 mm, sampled every 1 mm, all pen down."""
    x = np.linspace(-0.1, 0.1, 201)
    xy = np.column_stack([x, np.zeros_like(x)])
    pos = SURFACE.to_world(xy, 0.0)
    t = np.arange(x.size) * 0.01
    samples = TrajectorySamples(
        t, pos, np.zeros_like(pos), np.zeros_like(pos), np.ones(x.size, bool)
    )
    force = np.full(x.size, 2.0)
    stroke = StrokeInput(xy[[0, -1]], np.full(2, WIDTH_M))
    return WritingPlan(samples, (stroke,), SURFACE, force_n=force, width_m=np.full(x.size, WIDTH_M))


def _flown(plan: WritingPlan, offset_m: float, force_n: float) -> FlownWriting:
    shift = np.asarray(SURFACE.y_axis_enu) * offset_m
    tip = plan.samples.position_m_enu + shift
    width = HexarotorParams().pen.width_m(np.full(tip.shape[0], force_n))
    base = reference_base_m_enu(plan, HexarotorParams()) + shift
    return FlownWriting(
        t_s=plan.samples.t_s,
        reference_m_enu=plan.samples.position_m_enu,
        writing_point_m_enu=tip,
        pen_down=plan.samples.pen_down,
        ink_width_m=width,
        base_m_enu=base,
        force_n=np.full(tip.shape[0], force_n),
    )


def test_perfect_writing_scores_zero_error_and_full_overlap() -> None:
    plan = _line_plan()
    force = float(HexarotorParams().pen.force_n(np.array([WIDTH_M]))[0])
    score = KIND.score(plan, _flown(plan, 0.0, force), None)
    assert score.rmse_pen_down_m == pytest.approx(0.0, abs=1e-12)
    assert score.extra["rmse_base_m"] == pytest.approx(0.0, abs=1e-12)
    assert score.extra["force_rmse_n"] == pytest.approx(abs(force - 2.0))
    assert score.iou == pytest.approx(1.0, abs=0.02)


def test_half_width_offset_gives_a_third_iou() -> None:
    # Two 10 mm bands shifted by 5 mm: intersection 5 mm, union 15 mm -> IoU 1/3 (round caps
    # at the ends move it slightly).
    plan = _line_plan()
    force = float(HexarotorParams().pen.force_n(np.array([WIDTH_M]))[0])
    score = KIND.score(plan, _flown(plan, WIDTH_M / 2, force), None)
    assert score.iou == pytest.approx(1.0 / 3.0, abs=0.03)
    assert score.extra["rmse_ee_m"] == pytest.approx(WIDTH_M / 2)
    assert score.extra["rmse_base_m"] == pytest.approx(WIDTH_M / 2)


def test_typed_text_gets_a_tapered_width_profile_within_the_pen() -> None:
    pen = HexarotorParams().pen
    xy = np.column_stack([np.linspace(0.0, 0.3, 31), np.zeros(31)])
    (stroke,) = with_default_widths([StrokeInput(xy)], WallSettings())
    assert stroke.width_m is not None
    assert stroke.width_m[0] == pytest.approx(pen.width_min_m)
    assert stroke.width_m[-1] == pytest.approx(pen.width_min_m)
    assert stroke.width_m.max() <= pen.width_max_m
    assert stroke.width_m[15] > stroke.width_m[2] > stroke.width_m[0]


def test_a_two_point_stroke_gets_knots_so_its_profile_survives_planning() -> None:
    from vehicles.hexarotor_sponge.waypoints import periods_of, stroke_forces_n

    pen = HexarotorParams().pen
    (stroke,) = with_default_widths(
        [StrokeInput(np.array([[0.0, 0.0], [0.0, 0.5]]))], WallSettings()
    )
    assert stroke.xy_m[:, 1].tolist() == pytest.approx([0.0, 0.04, 0.25, 0.46, 0.5])
    force = stroke_forces_n(stroke, pen, 9e-3)
    (_, contact, _) = periods_of([stroke], [force], start_m=np.array([0, 0, 0.06]), standoff_m=0.03)
    # All five profile points stay waypoints (touch, press, 5 points, release).
    assert contact.force_n.size == 7
    assert contact.force_n[3] == pytest.approx(float(pen.force_n(np.array([stroke.width_m[2]]))[0]))


def test_kind_names_and_refuses_foreign_settings() -> None:
    assert KIND.name == "hexarotor-sponge"
    assert KIND.orientation == "vertical"
    with pytest.raises(TypeError, match="expects WallSettings"):
        KIND.score(_line_plan(), _flown(_line_plan(), 0.0, 2.0), object())
    with pytest.raises(ValueError, match=r"needs settings\.surface"):
        KIND.simulated_vehicle((0.0, 0.0, 1.0), WallSettings())


def test_live_vehicle_hovers_at_its_start() -> None:
    start = SURFACE.to_world(np.zeros((1, 2)), 0.05)[0]
    vehicle = KIND.simulated_vehicle(tuple(start), WallSettings(surface=SURFACE))

    class Hold:
        position_m_enu = tuple(start)
        velocity_mps_enu = (0.0, 0.0, 0.0)
        acceleration_mps2_enu = (0.0, 0.0, 0.0)
        pen_down = False
        force_n = None

    for _ in range(100):
        vehicle.step(Hold())
    state = vehicle.state()
    assert np.linalg.norm(np.asarray(state.pen_tip_m_enu) - start) < 0.01
    assert not state.pen_contact and state.pen_width_m == 0.0


def test_show_settings_become_the_kinds_settings() -> None:
    from pydantic import ValidationError

    from vehicles.hexarotor_sponge.kind import settings_from
    from vehicles.hexarotor_sponge.show_section import HexarotorKindSettings, PenSettings

    model = HexarotorKindSettings(
        v_max_mps=0.33, rotor_tilt_deg=30.0, pen=PenSettings(preload_n=0.8)
    )
    settings = settings_from(model, SURFACE)
    assert settings.plan.limits.v_max_mps == 0.33
    assert settings.plan.params.rotor_tilt_rad == pytest.approx(np.pi / 6)
    assert settings.fly.params.pen_preload_n == 0.8
    assert settings.surface == SURFACE
    with pytest.raises(ValidationError, match="force_max_n must be above force_min_n"):
        PenSettings(force_min_n=3.0, force_max_n=2.0)
    with pytest.raises(ValidationError, match="extra"):
        HexarotorKindSettings.model_validate({"v_max": 1.0})


def test_one_set_of_defaults_for_shows_and_fly() -> None:
    """A show whose ``hexarotor`` section is left at its defaults, or missing, builds exactly
    the settings ``skyquill fly --kind hexarotor-sponge`` plans and flies with (no show): each
    figure both state comes from ``vehicles.hexarotor_sponge.defaults``."""
    from showfile import load_show
    from vehicles.hexarotor_sponge import defaults
    from vehicles.hexarotor_sponge.kind import settings_from
    from vehicles.hexarotor_sponge.show_section import HexarotorKindSettings

    fly = KIND.settings(None, None)
    assert fly == WallSettings()
    built = settings_from(HexarotorKindSettings())
    pairs = {
        "rotor_tilt_deg -> params.rotor_tilt_rad": (
            built.plan.params.rotor_tilt_rad,
            fly.plan.params.rotor_tilt_rad,
        ),
        "thrust_max_n": (built.plan.params.thrust_max_n, fly.plan.params.thrust_max_n),
        "arm_length_m": (built.plan.params.arm_length_m, fly.plan.params.arm_length_m),
        "wall_friction": (built.plan.params.wall_friction, fly.plan.params.wall_friction),
        "v_max_mps": (built.plan.limits.v_max_mps, fly.plan.limits.v_max_mps),
        "a_max_mps2": (built.plan.limits.a_max_mps2, fly.plan.limits.a_max_mps2),
        "force_rate_max_nps": (
            built.plan.limits.force_rate_max_nps,
            fly.plan.limits.force_rate_max_nps,
        ),
        "reach_m": (built.plan.reach_m, fly.plan.reach_m),
        "pen.width_coefficients_m": (
            built.plan.params.pen.coefficients_m,
            fly.plan.params.pen.coefficients_m,
        ),
        "pen.force_min_n": (built.plan.params.pen.force_min_n, fly.plan.params.pen.force_min_n),
        "pen.force_max_n": (built.plan.params.pen.force_max_n, fly.plan.params.pen.force_max_n),
        "pen.stiffness_npm": (
            built.plan.params.pen_stiffness_npm,
            fly.plan.params.pen_stiffness_npm,
        ),
        "pen.preload_n": (built.plan.params.pen_preload_n, fly.plan.params.pen_preload_n),
        "pen.default_width_m": (built.plan.default_width_m, fly.plan.default_width_m),
        "pen.clamp_widths": (built.plan.clamp_widths, fly.plan.clamp_widths),
    }
    assert {name: pair for name, pair in pairs.items() if pair[0] != pair[1]} == {}
    assert built == fly  # and everything else, the flight's vehicle included
    assert fly.plan.params.rotor_tilt_rad == defaults.ROTOR_TILT_RAD
    # a show file with a wall writer and no ``hexarotor`` section: the same, on its wall
    show = load_show(SHOWS / "flying-calligrapher.yaml").model_copy(update={"hexarotor": None})
    vehicle = show.vehicles[0]
    on_wall = KIND.settings(show, vehicle.id)
    assert on_wall.surface is not None
    assert (on_wall.plan, on_wall.fly) == (fly.plan, fly.fly)


def test_report_draws_images_force_and_width() -> None:
    plan = _line_plan()
    fig = KIND.report(plan, _flown(plan, WIDTH_M / 2, 2.0), None, "line")
    titles = [ax.get_title() for ax in fig.axes]
    # 2 N draws 7.6 mm: band [1.2, 8.8] mm against [-5, 5] mm -> 3.8 / 13.8 = 0.28.
    assert titles[0] == "target (light), written (dark), both (blue): IoU 0.28"
    assert [ax.get_ylabel() for ax in fig.axes[1:]] == [
        "tip error [cm]",
        "normal force [N]",
        "line width [mm]",
    ]


def test_the_live_vehicle_and_the_batch_flight_are_one_closed_loop() -> None:
    plan = _line_plan()
    settings = WallSettings(fly=replace(FlySettings(), settle_s=0.0), surface=SURFACE)
    batch = fly_plan(plan, settings.fly, seed=3)
    s = plan.samples
    start = (
        float(s.position_m_enu[0, 0]),
        float(s.position_m_enu[0, 1]),
        float(s.position_m_enu[0, 2]),
    )
    live = KIND.simulated_vehicle(start, settings, seed=3)
    tips, forces = [], []
    for k in range(s.t_s.size):
        assert plan.force_n is not None
        live.step(
            LiveReference(
                tuple(s.position_m_enu[k]),
                tuple(s.velocity_mps_enu[k]),
                tuple(s.acceleration_mps2_enu[k]),
                bool(s.pen_down[k]),
                float(plan.force_n[k]),
            )
        )
        state = live.state()
        tips.append(state.pen_tip_m_enu)
        forces.append(state.force_n)
    np.testing.assert_array_equal(np.asarray(tips), batch.writing_point_m_enu)
    np.testing.assert_array_equal(np.asarray(forces), batch.force_n)
    assert (
        batch.force_n is not None and batch.force_n.max() > 1.0
    )  # it pressed on the wall: not two vehicles in free air

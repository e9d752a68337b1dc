"""The vehicle-kind seam: the registry, one set of defaults, one job-planning function, one loop."""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np
import pytest

from cli import cmd_plan
from kiosk.limits import Submission
from kiosk.preview import plan_preview
from kiosk.settings import settings_from_show
from planner import defaults
from planner.glyphs import text_glyph
from planner.limits import VehicleLimits
from planner.options import PlanOptions
from showfile import load_show
from showfile.models import ControllerSettings, Limits, PlanningSettings
from vehicles import UnknownKindError, kind_names
from vehicles.jobs import board_surface, plan_glyph, plan_job
from vehicles.kind import LiveReference
from vehicles.quadrotor_brush.flight import Flight
from vehicles.quadrotor_brush.flight_config import FlightConfig
from vehicles.quadrotor_brush.settings import (
    QuadrotorSettings,
    controller_config,
    plan_options,
    quadrotor_settings,
    world_params,
)
from vehicles.registry import vehicle_kind
from vehicles.surface import Surface

SHOWS = Path(__file__).resolve().parent.parent / "shows"


def test_the_registry_hands_out_rooms_and_names_the_kinds_it_has() -> None:
    kind = vehicle_kind("quadrotor-brush")
    assert kind.name == "quadrotor-brush" and kind.orientation == "horizontal"
    assert "quadrotor-brush" in kind_names()
    with pytest.raises(UnknownKindError, match=r"the kinds are: .*quadrotor-brush"):
        vehicle_kind("zeppelin-chalk")


def test_one_set_of_defaults_for_shows_plan_and_fly() -> None:
    limits, planning = Limits(), PlanningSettings()
    planner_limits = VehicleLimits()
    assert limits.a_max_mps2 == planner_limits.a_max_mps2
    assert limits.v_max_mps == planner_limits.v_max_mps
    assert limits.mass_kg == planner_limits.mass_kg
    assert limits.thrust_max_n == pytest.approx(planner_limits.thrust_max_n, abs=1e-9)
    assert limits.body_rate_max_radps == planner_limits.body_rate_max_radps
    options = PlanOptions()
    assert planning.write_height_m == options.write_height_m == defaults.WRITE_HEIGHT_M
    assert planning.clearance_m == options.clearance_m == defaults.CLEARANCE_M
    assert planning.margin_m == defaults.MARGIN_M
    assert planning.split_threshold_m == options.split_threshold_m
    assert planning.sample_rate_hz == options.sample_rate_hz
    parser = argparse.ArgumentParser()
    cmd_plan.add_arguments(parser)
    args = parser.parse_args(["--text", "A"])
    assert (args.v_max, args.mass, args.body_rate_max) == (
        limits.v_max_mps,
        limits.mass_kg,
        limits.body_rate_max_radps,
    )
    assert (args.write_height, args.clearance, args.margin) == (
        planning.write_height_m,
        planning.clearance_m,
        planning.margin_m,
    )
    # without a show, a kind's settings are those of a show left at its defaults
    settings = quadrotor_settings(None, None)
    assert settings.plan.limits == planner_limits
    assert settings.plan.write_height_m == planning.write_height_m
    brush = settings.flight.world.brush
    assert brush.write_height_m == pytest.approx(planning.write_height_m)
    assert settings.flight.controller.brush_lever_m == planning.write_height_m


def test_settings_without_a_show_are_a_default_show_files_built_without_pydantic() -> None:
    """``quadrotor_settings(None, None)`` skips the show file models (their import is a third
    of a one-off plan): it must still equal the settings of a show left at its defaults."""
    planning, limits, controller = PlanningSettings(), Limits(), ControllerSettings()
    plan = plan_options(planning, limits)
    world = world_params(plan.write_height_m, 0.0, controller.rate_hz)
    flight = FlightConfig(world, controller_config(controller.preset, plan.write_height_m))
    assert quadrotor_settings(None, None) == QuadrotorSettings(plan=plan, flight=flight)


def test_plan_job_writes_on_the_vehicles_own_board_with_its_show_settings() -> None:
    show = load_show(SHOWS / "airshow-2014.yaml")
    job = plan_job(show, "uav3", text_glyph("L"))
    board = show.board("b3")
    down = job.plan.samples.position_m_enu[job.plan.samples.pen_down]
    np.testing.assert_allclose(
        down[:, 2], board.center_m_enu[2] + show.planning.write_height_m, atol=0.006
    )
    local = job.plan.surface.to_surface(down)
    assert np.all(np.abs(local) <= np.asarray(board.writing_area_m) / 2.0)
    assert job.plan.feasibility["peak_speed_mps"] <= show.limits.v_max_mps + 1e-6


def test_the_kiosk_preview_plans_what_the_vehicle_will_fly() -> None:
    show = load_show(SHOWS / "solo.yaml")
    vehicle = show.vehicles[0]
    preview = plan_preview(Submission(text="永", strokes=None), settings_from_show(show))
    flown = plan_job(show, vehicle.id, text_glyph("永")).plan
    assert preview["duration_s"] == pytest.approx(flown.duration_s, abs=0.01)
    assert preview["turning_point_count"] == sum(len(tp) for tp in flown.turning_points_m)


def test_the_live_vehicle_and_the_batch_flight_are_one_closed_loop() -> None:
    kind = vehicle_kind("quadrotor-brush")
    base = kind.settings(None, None)
    settings = dataclasses.replace(
        base, flight=dataclasses.replace(base.flight, preroll_s=0.0, settle_s=0.0)
    )
    surface = Surface.of("horizontal", (0.0, 0.0, 0.0), 0.0)
    plan = plan_glyph(kind, settings, surface, text_glyph("L"), (0.4, 0.4), 0.0).plan
    batch = Flight([plan.samples], settings.flight, seed=5).run()
    commands = kind.command_reference(plan, settings)
    start = tuple(float(x) for x in commands.position_m_enu[0])
    live = kind.simulated_vehicle(start, settings, seed=5)  # type: ignore[arg-type]
    positions = []
    for p, v, a in zip(
        commands.position_m_enu,
        commands.velocity_mps_enu,
        commands.acceleration_mps2_enu,
        strict=True,
    ):
        positions.append(live.state().position_m_enu)
        live.step(LiveReference(tuple(p), tuple(v), tuple(a)))  # type: ignore[arg-type]
    k = min(len(positions), batch.t_s.shape[0])
    assert k > 100
    # the same loop: only the body reference's resampling onto the tick grid differs (~1e-5 m)
    np.testing.assert_allclose(np.asarray(positions[:k]), batch.position_m_enu[:k, 0], atol=1e-4)
    wandering = np.abs(batch.position_m_enu[:k, 0] - batch.position_m_enu[0, 0]).max()
    assert wandering > 0.1  # it did write: agreement is not two vehicles standing still


def test_board_surface_follows_the_show_board() -> None:
    show = load_show(SHOWS / "airshow-2014.yaml")
    board = show.board("b3")
    surface = board_surface(board)
    assert surface.origin_m_enu == board.center_m_enu and surface.orientation == "horizontal"

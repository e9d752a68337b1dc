"""The ground writers' show-file section and its translation into the room's settings."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest
import yaml
from pydantic import ValidationError

from vehicles.omni_wheel.check_route import FloorArea, RouteError, check_route
from vehicles.omni_wheel.floor_plan import DEFAULT_SETTINGS
from vehicles.omni_wheel.settings import omni_settings
from vehicles.omni_wheel.show_section import OmniWheelSettings, StepSettings

SHOW = Path(__file__).resolve().parents[1] / "shows" / "ground-writers.yaml"


def test_draft_show_section_gives_a_terrain_the_writers_can_cross() -> None:
    doc = yaml.safe_load(SHOW.read_text(encoding="utf-8"))
    settings = omni_settings(OmniWheelSettings.model_validate(doc["omni_wheel"]))
    assert settings.terrain.height_at_m(4.0) == pytest.approx(0.05)
    assert settings.geometry.friction_static == 1.0
    assert settings.geometry.friction_dynamic == pytest.approx(0.9)  # slides at 90 % of static
    boards = {b["id"]: b for b in doc["boards"]}
    for vehicle in doc["vehicles"]:
        board = boards[vehicle["board"]]
        area = FloorArea(board["id"], tuple(board["center_m_enu"]), 0.5 * max(board["size_m"]))
        check_route(tuple(vehicle["home_m_enu"]), area, settings.terrain)


def test_a_default_section_is_the_rooms_defaults_but_for_the_rubber_rollers() -> None:
    """One set of defaults (skyquill fly --kind omni-wheel without a show, and a show's section
    left at its defaults), but one deliberate difference: a show's rollers are rubber (1.0),
    the room's are Table 1's (0.3, which cannot climb a 50 mm step)."""
    geometry = DEFAULT_SETTINGS.geometry
    ratio = geometry.friction_dynamic / geometry.friction_static
    rubber = replace(geometry, friction_static=1.0, friction_dynamic=1.0 * ratio)
    assert omni_settings(OmniWheelSettings()) == replace(DEFAULT_SETTINGS, geometry=rubber)


def test_a_terrace_too_high_is_refused_by_name() -> None:
    section = OmniWheelSettings(steps=(StepSettings(x_m=1.5, height_m=0.3),))
    terrain = omni_settings(section).terrain
    with pytest.raises(
        RouteError, match=r"'east' is out of reach: the step at x=1.50 m is 0.300 m"
    ):
        check_route((0.0, -2.0, 0.0), FloorArea("east", (4.0, 0.0, 0.3), 1.3), terrain)


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        ({"speed_max_mps": 0.5}, "exceeds running_speed_mps"),
        ({"steps": [{"x_m": 2.0, "height_m": 0.1}, {"x_m": 1.0, "height_m": 0.2}]}, "increasing"),
        ({"marker_width": 0.04}, "Extra inputs are not permitted"),
    ],
)
def test_bad_sections_are_refused(fields: dict[str, object], message: str) -> None:
    with pytest.raises(ValidationError, match=message):
        OmniWheelSettings.model_validate(fields)

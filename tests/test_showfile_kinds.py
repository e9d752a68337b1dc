"""The seam between show files and vehicle kinds: the show file knows the kinds only through
their records in ``vehicles.ROOMS`` and their rooms' light ``show_section`` modules."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import typing
from pathlib import Path
from typing import Any

import pytest
from pydantic import BaseModel

from showfile import ShowFileError, parse_show
from showfile.models import Show
from vehicles import DEFAULT_KIND, ROOMS, Room
from vehicles.quadrotor_brush import KIND_NAME
from vehicles.registry import vehicle_kind

ROOT = Path(__file__).resolve().parents[1]

SOLO = """\
show_id: t
boards:
  - id: b1
    center_m_enu: [0, 0, 0.75]
    size_m: [1.4, 1.4]
    writing_area_m: [1.2, 1.2]
vehicles:
  - id: uav1
    kind: quadrotor-brush
    board: b1
    home_m_enu: [0, -1.2, 0]
"""


def _section_model(field_name: str) -> type[BaseModel]:
    """The model of the Show field ``field_name`` (typed ``Model | None``)."""
    annotation = Show.model_fields[field_name].annotation
    models = [a for a in typing.get_args(annotation) if a is not type(None)]
    assert len(models) == 1 and issubclass(models[0], BaseModel), annotation
    model: type[BaseModel] = models[0]
    return model


def _nested_models(model: type[BaseModel]) -> list[type[BaseModel]]:
    """``model`` and every model its fields hold (one level of tuples and unions)."""
    found = [model]
    for info in model.model_fields.values():
        args = typing.get_args(info.annotation) or (info.annotation,)
        for arg in args:
            if isinstance(arg, type) and issubclass(arg, BaseModel) and arg not in found:
                found += _nested_models(arg)
    return found


def test_each_rooms_kind_agrees_with_its_record() -> None:
    for name, room in ROOMS.items():
        kind = vehicle_kind(name)
        assert kind.name == name
        assert kind.orientation == room.orientation, name
        assert kind.phases(kind.settings(None, None)).route == room.transit_route, name
        # the autopilot flag: tests/test_showfile_load.py (it asks each kind's autopilot_world)


def test_a_vehicle_without_a_kind_is_of_the_default_kind_which_has_a_room() -> None:
    assert DEFAULT_KIND in ROOMS
    without_kind = SOLO.replace("    kind: quadrotor-brush\n", "")
    assert "kind:" not in without_kind
    show = parse_show(without_kind)
    assert show.vehicles[0].kind == DEFAULT_KIND


def test_the_brush_rooms_own_name_is_its_kinds() -> None:
    """``vehicles.quadrotor_brush.KIND_NAME`` names the brush without importing its kind."""
    assert ROOMS[KIND_NAME].kind_module == "vehicles.quadrotor_brush.kind"
    assert vehicle_kind(KIND_NAME).name == KIND_NAME


def test_each_kind_section_is_a_show_field_typed_by_its_rooms_model() -> None:
    sections = {room.section: room for room in ROOMS.values() if room.section is not None}
    assert set(sections) == {"hexarotor", "omni_wheel"}  # the YAML keys of the shipped shows
    for key, room in sections.items():
        package = room.kind_module.rsplit(".", 1)[0]
        assert _section_model(key).__module__ == f"{package}.show_section", key
    from_rooms = {
        name
        for name, info in Show.model_fields.items()
        if any(
            isinstance(arg, type) and arg.__module__.startswith("vehicles.")
            for arg in typing.get_args(info.annotation)
        )
    }
    assert from_rooms == set(sections)  # no room's section without its record


def test_the_rooms_sections_are_as_strict_as_the_rest_of_the_show_file() -> None:
    wanted = {
        key: Show.model_config[key] for key in ("frozen", "extra", "use_attribute_docstrings")
    }
    for room in ROOMS.values():
        if room.section is None:
            continue
        for model in _nested_models(_section_model(room.section)):
            config = {key: model.model_config.get(key) for key in wanted}
            assert config == wanted, model


def test_an_unknown_kind_is_refused_at_its_line_naming_the_kinds() -> None:
    with pytest.raises(ShowFileError) as info:
        parse_show(SOLO.replace("kind: quadrotor-brush", "kind: tricopter"), file="bad.yaml")
    problem = {p.field: p for p in info.value.problems}["vehicles[0].kind"]
    assert problem.line == 9
    assert problem.message == (
        "no vehicle kind 'tricopter'; the kinds are: hexarotor-sponge, omni-wheel, quadrotor-brush"
    )


def test_a_new_kind_needs_a_record_not_an_edit_of_the_show_file(monkeypatch: Any) -> None:
    monkeypatch.setitem(ROOMS, "quadrotor-pencil", Room("no.such.module", "vertical", 0.3))
    text = SOLO.replace("kind: quadrotor-brush", "kind: quadrotor-pencil")
    with pytest.raises(ShowFileError) as info:
        parse_show(text, file="bad.yaml")
    problem = {p.field: p for p in info.value.problems}["vehicles[0].board"]
    assert problem.message == (
        "a quadrotor-pencil writes on a vertical board, but board 'b1' is horizontal"
    )
    monkeypatch.setitem(ROOMS, "quadrotor-pencil", Room("no.such.module", "horizontal", 0.3))
    assert parse_show(text).vehicles[0].kind == "quadrotor-pencil"


TWO_HOMES = """\
show_id: t
boards:
  - {id: b1, center_m_enu: [-2, 0, 0.75], size_m: [1.4, 1.4], writing_area_m: [1.2, 1.2]}
  - {id: b2, center_m_enu: [2, 0, 0.75], size_m: [1.4, 1.4], writing_area_m: [1.2, 1.2]}
vehicles:
  - {id: first, kind: KIND, board: b1, home_m_enu: [0, -1.2, 0]}
  - {id: second, kind: KIND, board: b2, home_m_enu: [DX, -1.2, 0]}
"""


def _two_homes(kind: str, dx_m: float) -> str:
    return TWO_HOMES.replace("KIND", kind).replace("DX", str(dx_m))


def test_homes_closer_than_two_footprints_are_refused_at_the_second() -> None:
    parse_show(_two_homes("quadrotor-brush", 0.66))
    with pytest.raises(ShowFileError) as info:
        parse_show(_two_homes("quadrotor-brush", 0.64), file="bad.yaml")
    problem = {p.field: p for p in info.value.problems}["vehicles[1].home_m_enu"]
    assert problem.line == 7
    assert problem.message == (
        "0.64 m from the home of 'first': their footprints need 0.66 m "
        "(quadrotor-brush 0.33 m, quadrotor-brush 0.33 m)"
    )


def test_two_ground_writers_0_6_m_apart_are_refused() -> None:
    text = (ROOT / "shows" / "ground-writers.yaml").read_text()
    assert "home_m_enu: [0.0, -2.0, 0.0]" in text
    near = text.replace("home_m_enu: [0.0, -2.0, 0.0]", "home_m_enu: [-1.4, -2.0, 0.0]")
    parse_show(text)
    with pytest.raises(
        ShowFileError, match=r"0\.60 m from the home of 'ground1': their footprints need 1\.00 m"
    ):
        parse_show(near)


def test_each_kinds_footprint_holds_its_rooms_dimensions() -> None:
    from vehicles.hexarotor_sponge.params import HexarotorParams
    from vehicles.omni_wheel.floor_plan import DEFAULT_SETTINGS

    hexarotor = HexarotorParams()
    assert ROOMS["hexarotor-sponge"].footprint_radius_m >= max(
        hexarotor.rotor_radius_m + 0.127, hexarotor.arm_length_m
    )
    omni, g = DEFAULT_SETTINGS, DEFAULT_SETTINGS.geometry
    rear_m = g.middle_rear_m + g.wheel_radius_m + omni.pen_offset_m()  # behind the marker
    front_m = g.front_middle_m + g.wheel_radius_m - omni.pen_offset_m()
    assert ROOMS["omni-wheel"].footprint_radius_m >= math.hypot(
        max(rear_m, front_m), g.half_track_m
    )
    airshow_m = 0.40 / 2 + 0.127  # motor to motor (Phang et al.) and a 10-inch propeller
    assert ROOMS["quadrotor-brush"].footprint_radius_m >= airshow_m


def test_the_json_schema_lists_the_kinds_and_their_sections() -> None:
    schema = Show.model_json_schema()
    kind = schema["$defs"]["Vehicle"]["properties"]["kind"]
    assert kind["enum"] == sorted(ROOMS) and kind["default"] == "quadrotor-brush"
    assert kind["description"].startswith("What kind of vehicle it is")
    for room in ROOMS.values():
        if room.section is not None:
            assert room.section in schema["properties"], room.section


def test_loading_every_show_loads_no_kind_machinery() -> None:
    """The console and trust load show files: none of the planner, numerics, MuJoCo or CasADi."""
    heavy = ("casadi", "mujoco", "scipy", "numpy", "matplotlib", "planner", "sim")
    code = (
        "import json, sys\n"
        "from pathlib import Path\n"
        "from showfile import load_show\n"
        "shows = [load_show(p) for p in sorted(Path('shows').glob('*.yaml'))]\n"
        f"heavy = {heavy!r}\n"
        "loaded = sorted({m for m in sys.modules if m.split('.')[0] in heavy})\n"
        "print(json.dumps([len(shows), loaded]))"
    )
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, check=True
    )
    count, loaded = json.loads(out.stdout.strip().splitlines()[-1])
    assert count == len(list((ROOT / "shows").glob("*.yaml"))) and loaded == []


NOT_APPLIED: set[tuple[str, str]] = set()
"""Fields of the shared sections that no code reads yet (their description says so)."""


@pytest.mark.parametrize("section", ["limits", "planning", "controller"])
def test_every_field_of_the_shared_sections_names_the_kinds_that_read_it(section: str) -> None:
    """``limits``, ``planning`` and ``controller`` hold mostly the brush quadrotor's facts next
    to a few every kind reads: each field's schema description ends its own words with "Read by:"
    and a kind that has a room, or every kind (or nobody, for the fields not applied yet)."""
    schema = Show.model_json_schema()
    model = schema["properties"][section]["$ref"].rsplit("/", 1)[-1]
    for name, field in schema["$defs"][model]["properties"].items():
        readers = " ".join(field["description"].split()).split("Read by: ", 1)[1]
        allowed = {*ROOMS, "every kind"} | ({"nobody"} if (model, name) in NOT_APPLIED else set())
        assert any(readers.startswith(reader) for reader in allowed), (model, name, readers)

"""The seam between show files and vehicle kinds: the show file knows the kinds only through
their records in ``vehicles.ROOMS`` and their rooms' light ``show_section`` modules."""

from __future__ import annotations

import json
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
from vehicles import ROOMS, Room
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
        # the autopilot flag: tests/test_showfile_load.py (it asks each kind's autopilot_world)


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
    monkeypatch.setitem(ROOMS, "quadrotor-pencil", Room("no.such.module", "vertical"))
    text = SOLO.replace("kind: quadrotor-brush", "kind: quadrotor-pencil")
    with pytest.raises(ShowFileError) as info:
        parse_show(text, file="bad.yaml")
    problem = {p.field: p for p in info.value.problems}["vehicles[0].board"]
    assert problem.message == (
        "a quadrotor-pencil writes on a vertical board, but board 'b1' is horizontal"
    )
    monkeypatch.setitem(ROOMS, "quadrotor-pencil", Room("no.such.module", "horizontal"))
    assert parse_show(text).vehicles[0].kind == "quadrotor-pencil"


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

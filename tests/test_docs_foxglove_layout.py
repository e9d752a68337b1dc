"""``docs/foxglove-layout.json`` is the layout the script builds today, and every topic and field
it shows is one the scene writes (issue 36)."""

from __future__ import annotations

import json
import re
from pathlib import Path

from module_by_path import load_module

from scene.show_scene import (
    LOG_TOPIC,
    PATHS_TOPIC,
    PLOT_SCHEMA,
    PLOT_TOPIC,
    VEHICLES_TOPIC,
    VENUE_TOPIC,
)

ROOT = Path(__file__).resolve().parent.parent
SCRIPT = load_module("foxglove_layout", ROOT / "scripts" / "docs" / "foxglove_layout.py")


def test_the_committed_layout_is_the_scripts() -> None:
    committed = (ROOT / "docs" / "foxglove-layout.json").read_text(encoding="utf-8")
    assert committed == SCRIPT.rendered(), "run scripts/docs/foxglove_layout.py"


def test_every_panel_shows_a_topic_and_field_the_scene_writes() -> None:
    text = (ROOT / "docs" / "foxglove-layout.json").read_text(encoding="utf-8")
    layout = json.loads(text)
    assert layout["variables"] == {"vehicle": "uav1"}
    topics = set(re.findall(r'"(/[a-z/]+)"', text))
    assert {VENUE_TOPIC, VEHICLES_TOPIC, PATHS_TOPIC, LOG_TOPIC} <= topics
    series = re.findall(r'"value": "([^"]+)"', text)
    assert len(series) == 3
    for value in series:
        match = re.fullmatch(r"(/[a-z]+)\{vehicle_id==\$vehicle\}\.([a-z_]+)", value)
        assert match and match.group(1) == PLOT_TOPIC, value
        assert match.group(2) in PLOT_SCHEMA["properties"], value  # type: ignore[operator]

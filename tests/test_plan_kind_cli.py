"""``skyquill plan --kind K``: every kind planned through its room; PLAN.json holds the kind's own
plan (forces and widths where it plans them); brush options and ``--plot`` refused, exit 2."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from cli.main import main
from planner.glyphs import text_glyph
from planner.samples import TrajectorySamples
from vehicles.jobs import lay_out
from vehicles.kind import StrokeInput, WritingPlan
from vehicles.registry import vehicle_kind
from vehicles.surface import Surface

DATA = Path(__file__).parent / "data"
ROOT = Path(__file__).resolve().parents[1]


def _planned_directly(kind_name: str, text: str, centre_z_m: float) -> WritingPlan:
    """The plan of ``text`` made by the kind itself, on the 1 m area with 0.05 m margin."""
    kind = vehicle_kind(kind_name)
    glyph = lay_out(text_glyph(text), (1.0, 1.0), 0.05)
    strokes = [StrokeInput(np.asarray(s, dtype=np.float64)) for s in glyph.strokes]
    surface = Surface.of(kind.orientation, (0.0, 0.0, centre_z_m), 0.0)
    return kind.plan(strokes, surface, kind.settings(None, None))


def test_the_wall_kind_writes_its_forces_and_widths(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "plan.json"
    status = main(["plan", "--kind", "hexarotor-sponge", "--text", "I", "--margin", "0.05",
                   "--out", str(out)])  # fmt: skip
    assert status == 0, capsys.readouterr().err
    doc = json.loads(out.read_text(encoding="utf-8"))
    direct = _planned_directly("hexarotor-sponge", "I", 1.5)
    assert doc["format"] == "skyquill.plan/1" and doc["kind"] == "hexarotor-sponge"
    assert doc["duration_s"] == pytest.approx(direct.duration_s, abs=1e-6)
    samples = TrajectorySamples.from_json_dict(doc["samples"])
    assert samples.t_s.shape == direct.samples.t_s.shape
    np.testing.assert_allclose(samples.position_m_enu, direct.samples.position_m_enu, atol=1e-6)
    force, width = np.asarray(doc["samples"]["force_n"]), np.asarray(doc["samples"]["width_m"])
    assert direct.force_n is not None and direct.width_m is not None
    np.testing.assert_allclose(force, direct.force_n, atol=1e-6)
    np.testing.assert_allclose(width, direct.width_m, atol=1e-6)
    assert force[samples.pen_down].min() > 0.0 and width[samples.pen_down].min() > 0.0
    assert doc["surface"]["orientation"] == "vertical"
    assert doc["surface"]["origin_m_enu"] == [0.0, 0.0, 1.5]  # the wall's centre, as fly lays it
    assert doc["feasibility"]["peak_speed_mps"] <= doc["feasibility"]["v_max_mps"] + 1e-6
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("I for hexarotor-sponge: ") and lines[0].endswith(
        ", 1 stroke; feasible: yes"
    )
    assert "speed 0.2 of 0.2 m/s" in lines[1] and "force rate" in lines[1]


def test_the_ground_kind_plans_in_the_floor_plane(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "plan.json"
    assert main(["plan", "--kind", "omni-wheel", "--text", "I", "--out", str(out)]) == 0
    doc = json.loads(out.read_text(encoding="utf-8"))
    direct = _planned_directly("omni-wheel", "I", 0.0)
    assert doc["duration_s"] == pytest.approx(direct.duration_s, abs=1e-6)
    assert doc["kind"] == "omni-wheel" and doc["surface"]["orientation"] == "floor"
    assert "force_n" not in doc["samples"] and "width_m" not in doc["samples"]
    assert np.allclose(np.asarray(doc["samples"]["p"])[:, 2], 0.0)
    assert doc["feasibility"]["accel_max_mps2"] == [0.25, 0.15]
    assert "of 0.25, 0.15 m/s^2" in capsys.readouterr().out.splitlines()[1]


@pytest.mark.parametrize(
    ("extra", "flag"),
    [
        (["--v-max", "0.5"], "--v-max"),  # the brush's default value, given: still refused
        (["--no-resegment"], "--no-resegment"),
        (["--write-height", "0.2"], "--write-height"),
        (["--a-max", "1", "1", "1"], "--a-max"),
        (["--solver", "osqp"], "--solver"),
    ],
)
def test_a_brush_option_is_refused_for_another_kind(
    extra: list[str], flag: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["plan", "--kind", "hexarotor-sponge", "--text", "I", *extra]) == 2
    captured = capsys.readouterr()
    assert captured.err == (
        f"skyquill plan: {flag} is an option of quadrotor-brush, not of hexarotor-sponge\n"
    )
    assert captured.out == ""  # refused before planning


def test_plot_is_refused_for_a_kind_without_a_plan_figure(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    plot = tmp_path / "plot.png"
    assert main(["plan", "--kind", "omni-wheel", "--text", "I", "--plot", str(plot)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("skyquill plan: --plot draws quadrotor-brush plans only")
    assert "skyquill fly --kind omni-wheel --report DIR" in err and err.count("\n") == 1
    assert not plot.exists()


def test_a_bad_strokes_file_is_named_with_its_stroke_and_point(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "bad.json"
    strokes = [[[0, 0], [10, 10]], [[1, 1], [2, 2], [3, "x"]]]
    bad.write_text(json.dumps({"units": "px", "y_axis": "down", "strokes": strokes}))
    assert main(["plan", "--kind", "omni-wheel", "--strokes", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"skyquill plan: error: {bad}: stroke 1, point 2: ")
    assert err.count("\n") == 1


def test_a_kinds_own_planning_error_names_the_stroke(capsys: pytest.CaptureFixture[str]) -> None:
    """A 4 m character on the wall lies beyond the hexarotor's 1.5 m reach."""
    strokes = DATA / "l_tick_m_up.json"
    status = main(["plan", "--kind", "hexarotor-sponge", "--strokes", str(strokes),
                   "--width", "4", "--height", "4"])  # fmt: skip
    assert status == 2
    err = capsys.readouterr().err
    assert err.startswith(f"skyquill plan: error: {strokes}: stroke 0, point ")
    assert "beyond the reach 1.5 m" in err and err.count("\n") == 1


def test_the_brush_kind_named_is_the_default_plan(tmp_path: Path) -> None:
    named, default = tmp_path / "named.json", tmp_path / "default.json"
    assert main(["plan", "--kind", "quadrotor-brush", "--text", "L", "--out", str(named)]) == 0
    assert main(["plan", "--text", "L", "--v-max", "0.5", "--out", str(default)]) == 0
    docs = [json.loads(path.read_text(encoding="utf-8")) for path in (named, default)]
    for doc in docs:
        doc.pop("timing_ms")
    assert docs[0] == docs[1] and docs[0]["format"] == "skyquill.traj/1"


def test_planning_another_kind_loads_neither_the_agent_nor_plotting() -> None:
    """The CLI reaches a kind through its room only (a fresh interpreter)."""
    code = (
        "import contextlib, io, json, sys\n"
        "from cli.main import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    assert main(['plan', '--kind', 'omni-wheel', '--text', 'I']) == 0\n"
        "print(json.dumps(sorted(m for m in sys.modules\n"
        "                        if m.startswith(('vehicle_agent', 'matplotlib', 'kiosk')))))"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True,
                         text=True, check=True)  # fmt: skip
    assert json.loads(out.stdout.strip().splitlines()[-1]) == []


@pytest.mark.parametrize("kind", ["quadrotor-brush", "omni-wheel"])
def test_an_output_that_cannot_be_written_is_one_line(
    kind: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "no-such-dir" / "plan.json"
    assert main(["plan", "--kind", kind, "--text", "L", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"skyquill plan: error: cannot write {out}: No such file or directory"

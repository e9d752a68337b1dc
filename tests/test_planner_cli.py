"""``skyquill plan``: writes TRAJ.json and a PNG; errors name file, stroke and point, exit 2."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from cli.main import main
from planner.samples import TrajectorySamples

DATA = Path(__file__).parent / "data"


def test_plan_text_writes_traj_json_and_png(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out, plot = tmp_path / "traj.json", tmp_path / "plot.png"
    status = main(["plan", "--text", "L", "--out", str(out), "--plot", str(plot), "--rate", "120"])
    assert status == 0, capsys.readouterr().err
    doc = json.loads(out.read_text())
    samples = TrajectorySamples.from_json_dict(doc["samples"])
    # on the 120 Hz grid (the last sample closes the plan, off the grid; times rounded to 1 us)
    assert np.diff(samples.t_s)[:-1] == pytest.approx(1.0 / 120.0, abs=2e-6)
    assert samples.duration_s == pytest.approx(doc["duration_s"], abs=1e-6)
    assert samples.pen_down.any() and not samples.pen_down[0]
    assert doc["limits"]["a_max"] == [0.8, 0.8, 0.5] and doc["limits"]["v_max"] == 0.5
    assert set(doc["timing_ms"]) >= {"path", "initial_times", "resegment", "feasibility", "total"}
    assert doc["feasibility"]["feasible"] is True
    assert [len(tp) for tp in doc["turning_points"]] == [2, 2]  # Hershey L: two strokes
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    head = capsys.readouterr().out.splitlines()[0]
    assert head.startswith("L for quadrotor-brush: ") and head.endswith("2 strokes; feasible: yes")


def test_plan_strokes_file_with_options(tmp_path: Path) -> None:
    out = tmp_path / "traj.json"
    status = main(
        [
            "plan",
            "--strokes",
            str(DATA / "l_tick_m_up.json"),
            "--out",
            str(out),
            "--a-max",
            "0.6",
            "--v-max",
            "0.4",
            "--solver",
            "clarabel",
            "--board-center",
            "1",
            "2",
            "0.5",
            "--total-time",
            "20",
        ]
    )
    assert status == 0
    doc = json.loads(out.read_text())
    assert doc["duration_s"] == pytest.approx(20.0)
    assert doc["limits"]["a_max"] == [0.6, 0.6, 0.6]
    assert doc["feasibility"]["peak_speed_mps"] <= 0.4
    assert min(p[2] for p in doc["samples"]["p"]) >= 0.5 + 0.3 - 1e-6


def test_bad_point_reports_file_stroke_point(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "bad.json"
    strokes = [
        [[0, 0], [10, 10]],
        [[0, 0], [1, 1]],
        [[5, 5], [6, 6]],
        [[1, 1], [2, 2], [3, 3], [4, 4], [5, 5], [6, 6], [7, 7], [8, "x"]],
    ]
    bad.write_text(json.dumps({"units": "px", "y_axis": "down", "strokes": strokes}))
    assert main(["plan", "--strokes", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"skyquill plan: error: {bad}: stroke 3, point 7: ")


def test_infeasible_request_exits_2_naming_the_limit(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["plan", "--text", "L", "--total-time", "2"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("skyquill plan: error: <text>: ")
    assert "acceleration" in err or "speed" in err


def test_missing_file_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["plan", "--strokes", str(tmp_path / "none.json")]) == 2
    assert "cannot read" in capsys.readouterr().err

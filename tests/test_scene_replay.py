"""``skyquill replay SHOW JOB``: one flown job's files become a Foxglove recording whose every
channel decodes with its schema: the vehicle where it flew, the whole plan, the ink, tracking
error to plot, the metrics in the log (issue 36)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from job_traces import recorded_trace, solo_job
from mcap.reader import make_reader
from scene_decode import decoded

from cli.main import main as skyquill
from showfile import dump_show
from vehicle_agent.jobs import job_metrics, write_job_report

OFFSET_M = np.array([0.01, 0.0, 0.0])
"""The made-up flight is the plan moved 1 cm east."""


def _flown_job(tmp_path: Path, *, brush_m: float | None = None) -> Path:
    """A compact job j1 (一) on uav1 flown 1 cm east of its plan, and its show file; with
    ``brush_m``, a backend that knows its brush, whose tip hangs that far below the body."""
    setup, prepared = solo_job(tmp_path, "compact")
    s = prepared.samples
    flown = s.position_m_enu + OFFSET_M
    n = s.t_s.size
    pen = {} if brush_m is None else {
        "pen_contact": s.pen_down, "pen_tip_m_enu": flown - [0.0, 0.0, brush_m],
        "pen_width_m": np.full(n, 0.004)}  # fmt: skip
    trace = recorded_trace(
        "j1", 1, s.t_s, flown, s.velocity_mps_enu, s.position_m_enu, s.pen_down, **pen
    )
    write_job_report(setup, prepared, trace, job_metrics(setup, prepared, trace))
    show_path = tmp_path / "solo.yaml"
    dump_show(setup.show, show_path)
    return show_path


def test_a_job_replayed_shows_where_it_flew_its_plan_and_its_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    show_path = _flown_job(tmp_path)
    monkeypatch.chdir(tmp_path)
    assert skyquill(["replay", str(show_path), "j1"]) == 0
    out = tmp_path / "j1-uav1-1.mcap"
    assert str(out.name) in capsys.readouterr().out
    topics: dict[str, list[object]] = {}
    with out.open("rb") as f:
        for schema, channel, message in make_reader(f).iter_messages():
            assert schema is not None
            value = decoded(channel.message_encoding, schema.name, schema.data, message.data)
            topics.setdefault(channel.topic, []).append(value)
    with np.load(tmp_path / "jobs" / "j1-uav1-1" / "flight.npz") as flight:
        points = flight["writing_point_m_enu"]
        plan = flight["reference_position_m_enu"]
    frames = [m.transforms[0] for m in topics["/tf"]]  # type: ignore[attr-defined]
    assert len(frames) == len(points)
    assert [frames[-1].translation.x, frames[-1].translation.y] == pytest.approx(points[-1][:2])
    errors = [p["tracking_error_m"] for p in topics["/plot"]]  # type: ignore[index]
    assert np.median(errors) == pytest.approx(0.01, abs=1e-4)  # the 1 cm it was moved
    whole_plan = topics["/scene/paths"][0].entities[0].lines[0]  # type: ignore[attr-defined]
    assert len(whole_plan.points) == len(plan)
    (metrics,) = topics["/log"]
    assert "rmse_m" in metrics.message and metrics.name == "metrics"  # type: ignore[attr-defined]
    assert {"/scene/venue", "/scene/vehicles"} <= topics.keys()


def test_an_unknown_job_or_attempt_is_one_line_naming_what_is_kept(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    show_path = _flown_job(tmp_path)
    assert skyquill(["replay", str(show_path), "j9"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no files of job 'j9'" in err and "j1" in err
    assert skyquill(["replay", str(show_path), "j1", "--attempt", "3"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no attempt 3 (kept: 1)" in err


def test_a_replay_hangs_the_writing_point_below_the_vehicle_and_inks_there(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    show_path = _flown_job(tmp_path, brush_m=0.3)
    monkeypatch.chdir(tmp_path)
    assert skyquill(["replay", str(show_path), "j1"]) == 0
    topics: dict[str, list[object]] = {}
    with (tmp_path / "j1-uav1-1.mcap").open("rb") as f:
        for schema, channel, message in make_reader(f).iter_messages():
            assert schema is not None
            value = decoded(channel.message_encoding, schema.name, schema.data, message.data)
            topics.setdefault(channel.topic, []).append(value)
    with np.load(tmp_path / "jobs" / "j1-uav1-1" / "flight.npz") as flight:
        base, tips = flight["base_m_enu"], flight["writing_point_m_enu"]
    body, tip = topics["/tf"][-1].transforms[:2]  # type: ignore[attr-defined]
    assert [body.translation.x, body.translation.y, body.translation.z] == pytest.approx(base[-1])
    assert (tip.parent_frame_id, tip.child_frame_id) == ("uav1", "uav1/writing_point")
    offset = [tip.translation.x, tip.translation.y, tip.translation.z]
    assert offset == pytest.approx([0.0, 0.0, -0.3], abs=1e-5)  # float32 files
    paths = topics["/scene/paths"][-1].entities[0]  # type: ignore[attr-defined]
    ink = next(line for line in paths.lines if line.type == 2)  # LINE_LIST
    ink_xyz = {tuple(round(c, 4) for c in (p.x, p.y, p.z)) for p in ink.points}
    assert ink_xyz and ink_xyz <= {tuple(round(float(c), 4) for c in tip) for tip in tips}

"""The live agent's path for the wall hexarotor and the ground writer (job runner + sim backend,
one process, no bus): phases from the kind, the planned force reaching the wall, the step climbed
on the way to a floor area, each kind's figures in the done report and the show's writing bounds
deciding ``done``; bad input refused with one clear line and the vehicle left on the ground (a
wall whose writing area lies beyond the reach is refused by the show file already:
tests/test_showfile_load.py)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from live_kinds import LiveRun

from bus.messages import JobAssignment
from showfile import parse_show

SHOWS = Path(__file__).resolve().parents[1] / "shows"
WALL_SHOW = (SHOWS / "flying-calligrapher.yaml").read_text(encoding="utf-8")
GROUND_SHOW = (SHOWS / "ground-writers.yaml").read_text(encoding="utf-8")
FLIGHT = ["climb", "transit", "settle", "write", "return", "land", "ground"]


def _strokes(width_m: float) -> dict[str, Any]:
    points = [{"x": 0.0, "y": 0.0, "w": width_m}, {"x": 0.3, "y": 0.0, "w": width_m},
              {"x": 0.3, "y": 0.3, "w": width_m}]  # fmt: skip
    return {"units": "m", "y_axis": "up", "strokes": [points]}


def _run(text: str, vehicle_id: str, job: JobAssignment, max_s: float) -> LiveRun:
    run = LiveRun(parse_show(text), vehicle_id)
    assert run.assign(job)
    run.until_back(max_s)
    return run


@pytest.mark.slow
def test_the_wall_hexarotor_writes_with_its_planned_force_and_reports_its_figures() -> None:
    run = _run(WALL_SHOW, "calligrapher", JobAssignment(job_id="j1", text="I", attempt=1), 120.0)
    assert run.phases == FLIGHT
    (report,) = [r for r in run.reports if r.event in ("done", "failed")]
    assert report.event == "done", report
    metrics = report.metrics
    assert metrics is not None and metrics.iou is not None and metrics.iou >= 0.6
    assert metrics.rmse_pen_down_m <= 0.015
    assert {"rmse_ee_m", "force_rmse_n", "width_rmse_m"} <= set(metrics.extra)
    assert metrics.extra["force_rmse_n"] < 0.6, metrics.extra  # batch flight: 0.31-0.38 N
    (trace,) = run.finished
    flown, contact = trace.flown, trace.flown.extra.get("pen_contact")
    assert trace.pen_known and flown.force_n is not None and contact is not None
    planned = run.prepared["j1"].force_n
    assert planned is not None and 0.9 * planned.max() < flown.force_n.max() < 1.2 * planned.max()
    assert not contact[0] and contact.any()  # contact made by the plan
    forces = [t.force_n for t in run.telemetry if t.state == "writing"]
    assert max(f or 0.0 for f in forces) > 1.0
    assert all(t.force_n in (None, 0.0) for t in run.telemetry if t.state == "taking_off")
    wanted = [t.force_reference_n for t in run.telemetry if t.state == "writing"]
    assert None not in wanted and max(wanted) == pytest.approx(planned.max(), rel=0.05)  # type: ignore[type-var]


@pytest.mark.slow
def test_a_wall_job_outside_the_shows_bounds_is_failed_not_done() -> None:
    text = WALL_SHOW.replace("iou_min: 0.6", "iou_min: 0.95")
    text = text.replace("writing_area_m: [0.5, 0.5]", "writing_area_m: [0.2, 0.2]")
    run = _run(text, "calligrapher", JobAssignment(job_id="j1", text="一", attempt=1), 90.0)
    (report,) = [r for r in run.reports if r.event in ("done", "failed")]
    assert report.event == "failed" and report.error is not None, report
    assert report.error.code == "writing_bounds" and "IoU" in report.error.message
    assert report.metrics is not None and "force_rmse_n" in report.metrics.extra


@pytest.mark.slow
def test_a_ground_writer_climbs_to_its_terrace_writes_and_drives_home() -> None:
    text = GROUND_SHOW.replace("writing_area_m: [2.2, 2.2]", "writing_area_m: [0.6, 0.6]")
    text = text.replace("home_m_enu: [0.0, -2.0, 0.0]", "home_m_enu: [0.8, -0.8, 0.0]")  # nearer
    east = "center_m_enu: [4.0, 0.0, 0.05], yaw_deg: 0, size_m: [2.6, 2.6]"
    assert east in text  # a smaller terrace area just past the step (x = 1.5 m): a shorter drive
    text = text.replace(east, "center_m_enu: [2.3, 0.0, 0.05], yaw_deg: 0, size_m: [1.2, 1.2]")
    run = _run(text, "ground2", JobAssignment(job_id="j1", text="一", attempt=1), 200.0)
    assert run.phases == FLIGHT
    (report,) = [r for r in run.reports if r.event in ("done", "failed")]
    assert report.event == "done", report
    metrics = report.metrics
    assert metrics is not None and metrics.iou is not None and metrics.iou >= 0.6
    assert metrics.rmse_pen_down_m <= 0.02 and metrics.written is not None
    (trace,) = run.finished
    base = trace.flown.base_m_enu
    assert base is not None and np.allclose(base[:, 2], 0.05, atol=0.01)  # on the terrace
    home = np.asarray(run.show.vehicle("ground2").home_m_enu)
    assert np.linalg.norm(np.asarray(run.vehicle.snapshot().position_m_enu) - home) < 0.05
    assert all(t.position_m_enu[2] < 0.06 for t in run.telemetry)  # never "took off"


@pytest.mark.parametrize(
    ("width_m", "words"),
    [(0.03, "width 30.00 mm is outside the pen's range"), (0.0, "w must be in (0, 1] m")],
)
def test_a_wall_job_it_cannot_write_is_reported_in_one_line_and_it_stays_down(
    width_m: float, words: str
) -> None:
    job = JobAssignment(job_id="j1", strokes=_strokes(width_m), attempt=1)
    run = LiveRun(parse_show(WALL_SHOW), "calligrapher")
    assert run.assign(job)
    for _ in range(5):
        run.tick()
    (report,) = run.reports
    assert report.event == "failed" and report.error is not None
    assert report.error.code == "plan_failed" and words in report.error.message
    assert "\n" not in report.error.message and report.retry_after_s is None
    assert run.phases == ["ground"] and run.vehicle.mode == "idle"  # never took off
    assert run.assign(JobAssignment(job_id="j2", text="I", attempt=1))  # free for the next

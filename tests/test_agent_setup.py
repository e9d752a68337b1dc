"""A vehicle set up from its show file: layout on its board, planning, metrics of a flown job."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from job_traces import recorded_trace, solo_job

from bus.messages import JobAssignment
from planner.errors import PlannerError
from showfile import load_show
from vehicle_agent.jobs import job_metrics, prepare_job, write_job_picture, write_job_report
from vehicle_agent.setup import vehicle_setup

SHOWS = Path(__file__).resolve().parent.parent / "shows"


@pytest.fixture(scope="module")
def airshow_uav3():  # type: ignore[no-untyped-def]
    return vehicle_setup(load_show(SHOWS / "airshow-2014.yaml"), "uav3", time_scale=4.0)


def test_setup_takes_board_heights_and_rates_from_the_show(airshow_uav3) -> None:  # type: ignore[no-untyped-def]
    setup = airshow_uav3
    cfg = setup.runner_config
    assert cfg.board_id == "b3" and cfg.home_m_enu == (1.0, -1.2, 0.0)
    assert cfg.cruise_z_m == pytest.approx(0.75 + 0.25 + 0.05)
    assert cfg.telemetry_period_s == pytest.approx(4.0 / 20.0)  # 20 Hz of wall time
    assert setup.surface.origin_m_enu == (1.0, 0.0, 0.75)


def test_a_job_is_laid_out_inside_its_board_area_and_planned(airshow_uav3) -> None:  # type: ignore[no-untyped-def]
    setup = airshow_uav3
    prepared = prepare_job(setup, JobAssignment(job_id="j1", text="L"))
    s = prepared.samples
    assert s.position_m_enu[0, 2] == pytest.approx(setup.runner_config.cruise_z_m, abs=1e-6)
    np.testing.assert_allclose(s.velocity_mps_enu[[0, -1]], 0.0, atol=1e-6)
    down = s.position_m_enu[s.pen_down]
    assert down.shape[0] > 100
    np.testing.assert_allclose(down[:, 2], 0.75 + 0.25, atol=0.006)
    assert np.all(np.abs(down[:, 0] - 1.0) <= 0.6) and np.all(np.abs(down[:, 1]) <= 0.6)
    assert np.ptp(down[:, 1]) > 0.9  # fitted to the 1.2 m area less margins
    assert prepared.command_samples is not None
    np.testing.assert_allclose(
        prepared.command_samples.position_m_enu[:, 2], s.position_m_enu[:, 2]
    )


def test_default_controller_aims_the_brush_tip_with_a_body_reference() -> None:
    setup = vehicle_setup(load_show(SHOWS / "solo.yaml"), "uav1")
    prepared = prepare_job(setup, JobAssignment(job_id="j1", text="L"))
    assert prepared.command_samples is not None
    shift = prepared.command_samples.position_m_enu - prepared.samples.position_m_enu
    assert 0.0 < np.abs(shift[:, :2]).max() < 0.05
    np.testing.assert_allclose(shift[:, 2], 0.0)


def test_a_job_that_cannot_be_laid_out_raises_a_planner_error(airshow_uav3) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(PlannerError):
        prepare_job(airshow_uav3, JobAssignment(job_id="j1", text="\u0378"))
    with pytest.raises(PlannerError):
        prepare_job(airshow_uav3, JobAssignment(job_id="j1", strokes={"strokes": "no"}))


def test_metrics_of_a_perfectly_flown_job(airshow_uav3) -> None:  # type: ignore[no-untyped-def]
    setup = airshow_uav3
    prepared = prepare_job(setup, JobAssignment(job_id="j1", text="L"))
    s = prepared.samples
    tip = s.position_m_enu - np.array([0.0, 0.0, 0.25])  # hanging straight down onto the board
    width = np.where(s.pen_down, 0.02, 0.0)
    trace = recorded_trace(
        "j1",
        1,
        s.t_s,
        s.position_m_enu,
        s.velocity_mps_enu,
        s.position_m_enu,
        s.pen_down,
        s.pen_down.copy(),
        tip,
        width,
    )
    metrics = job_metrics(setup, prepared, trace)
    assert metrics.rmse_m == pytest.approx(0.0, abs=1e-9)
    assert metrics.rmse_pen_down_m == pytest.approx(0.0, abs=1e-9)
    assert metrics.iou == pytest.approx(1.0)
    assert metrics.duration_s == pytest.approx(s.duration_s)
    shifted = tip + np.array([0.01, 0.0, 0.0])
    moved = recorded_trace(
        "j1",
        1,
        s.t_s,
        s.position_m_enu + np.array([0.01, 0.0, 0.0]),
        s.velocity_mps_enu,
        s.position_m_enu,
        s.pen_down,
        s.pen_down.copy(),
        shifted,
        width,
    )
    worse = job_metrics(setup, prepared, moved)
    assert worse.rmse_m == pytest.approx(0.01) and worse.max_error_m == pytest.approx(0.01)
    assert worse.iou is not None and 0.2 < worse.iou < 0.7  # a 2 cm stroke moved by 1 cm


@pytest.mark.parametrize("detail", ["full", "compact"])
def test_a_flown_job_is_recorded_next_to_the_database(tmp_path: Path, detail: str) -> None:
    setup, prepared = solo_job(tmp_path, detail)
    s = prepared.samples
    trace = recorded_trace(
        "j1", 2, s.t_s, s.position_m_enu, s.velocity_mps_enu, s.position_m_enu, s.pen_down, None
    )
    metrics = job_metrics(setup, prepared, trace)
    assert metrics.iou is None and metrics.rmse_m == 0.0  # no brush data: body errors only
    out = write_job_report(setup, prepared, trace, metrics)
    assert out == tmp_path / "jobs" / "j1-uav1-2"
    summary = json.loads((out / "metrics.json").read_text())
    assert summary["metrics"]["rmse_m"] == 0.0 and summary["attempt"] == 2
    with np.load(out / "flight.npz") as flight:
        if detail == "full":
            traj = json.loads((out / "TRAJ.json").read_text())
            assert len(traj["samples"]["t"]) == s.t_s.shape[0]
        else:  # the reference rides with the flight, at the same rate
            assert not (out / "TRAJ.json").exists()
            np.testing.assert_array_equal(flight["reference_t_s"], flight["t_s"])
        assert "pen_contact" not in flight and not flight["pen_known"]
        if detail == "full":
            np.testing.assert_array_equal(flight["writing_point_m_enu"], s.position_m_enu)
        else:  # 20 Hz in float32: a 100 Hz flight in a fifth of the ticks, within 0.1 mm
            kept = flight["t_s"]
            assert kept[0] == s.t_s[0] and kept[-1] == pytest.approx(s.t_s[-1])
            assert np.all(np.diff(kept)[:-1] >= 0.05 - 1e-9) and len(kept) <= len(s.t_s) // 5 + 2
            where = np.searchsorted(s.t_s, kept - 1e-9)
            np.testing.assert_allclose(
                flight["writing_point_m_enu"], s.position_m_enu[where], atol=1e-4
            )


def test_a_flown_job_gets_a_report_picture_and_none_without_brush_data(tmp_path: Path) -> None:
    setup = vehicle_setup(load_show(SHOWS / "solo.yaml"), "uav1")
    prepared = prepare_job(setup, JobAssignment(job_id="j1", text="一"))
    s = prepared.samples
    tip = s.position_m_enu - np.array([0.0, 0.0, 0.25])
    width = np.where(s.pen_down, 0.02, 0.0)
    args = ("j1", 1, s.t_s, s.position_m_enu, s.velocity_mps_enu, s.position_m_enu, s.pen_down)
    trace = recorded_trace(*args, s.pen_down.copy(), tip, width)
    path = write_job_picture(setup, prepared, trace, tmp_path)
    assert path == tmp_path / "report.png"
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert [p.name for p in tmp_path.iterdir()] == ["report.png"]  # no partial file left
    assert write_job_picture(setup, prepared, recorded_trace(*args, None), tmp_path / "x") is None

"""The agent paces each job to its vehicle (show ``planning.pace: tracking``): the first job at
the cautious stretch, the tracking identified from what it flew and kept on disk, the next job
at the pace predicted to meet the target, and the prediction checked against the flight."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from job_traces import recorded_trace

from bus.messages import JobAssignment
from showfile import load_show
from vehicle_agent.jobs import job_metrics, prepare_job, writing_plan
from vehicle_agent.pace import model_path
from vehicle_agent.setup import VehicleSetup, vehicle_setup

SHOWS = Path(__file__).resolve().parent.parent / "shows"
LAG_S = 0.04
"""The made-up vehicle's first-order lag: too slow to write the brush quadrotor's plan at the
limits within 6 mm (it needs about twice the time)."""


def paced_solo(tmp_path: Path) -> VehicleSetup:
    show = load_show(SHOWS / "solo.yaml")
    planning = show.planning.model_copy(update={"pace": "tracking"})
    storage = show.storage.model_copy(update={"database": tmp_path / "show.sqlite3"})
    return vehicle_setup(show.model_copy(update={"planning": planning, "storage": storage}), "uav1")


def fly(setup: VehicleSetup, job_id: str, text: str, seed: int) -> tuple[dict[str, float], float]:
    """Plan ``text``, fly it on a vehicle whose body follows its setpoints through a first-order
    lag plus 1 mm of noise, the brush 0.25 m below; the metrics' ``extra`` and the flown
    pen-down RMSE."""
    prepared = prepare_job(setup, JobAssignment(job_id=job_id, text=text))
    s, sent = prepared.samples, prepared.command_samples
    assert sent is not None
    dt_s = float(s.t_s[1] - s.t_s[0])
    body = np.empty_like(sent.position_m_enu)
    body[0] = sent.position_m_enu[0]
    for k in range(1, body.shape[0]):
        body[k] = body[k - 1] + dt_s / LAG_S * (sent.position_m_enu[k - 1] - body[k - 1])
    body += np.random.default_rng(seed).normal(0.0, 0.001 / np.sqrt(3.0), body.shape)
    tip = body - np.array([0.0, 0.0, 0.25])
    width = np.full(s.t_s.shape, 0.02)
    args = (s.t_s, body, s.velocity_mps_enu, s.position_m_enu, s.pen_down)  # the tip reference
    trace = recorded_trace(job_id, 1, *args, s.pen_down, tip, width)
    metrics = job_metrics(setup, prepared, trace)
    assert writing_plan(prepared).pace is not None
    return metrics.extra, metrics.rmse_pen_down_m


def test_a_vehicle_is_paced_to_its_identified_tracking(tmp_path: Path) -> None:
    setup = paced_solo(tmp_path)
    first, first_rmse_m = fly(setup, "j1", "永", seed=1)
    assert first["pace_stretch"] == 2.0 and "pace_predicted_rmse_pen_down_m" not in first
    kept = json.loads(model_path(setup.show, "uav1").read_text(encoding="utf-8"))
    assert kept["last_job"]["flown_rmse_mm"] == pytest.approx(first_rmse_m * 1e3, abs=0.01)
    assert kept["lag_s"] > 0.0

    # identified on 永 at stretch 2, the vehicle writes 水 at its own pace, near the target
    second, second_rmse_m = fly(setup, "j2", "水", seed=2)
    assert 1.0 < second["pace_stretch"] < 4.0
    predicted = second["pace_predicted_rmse_pen_down_m"]
    assert predicted == pytest.approx(0.006, rel=1e-6)
    assert second_rmse_m == pytest.approx(predicted, rel=0.25)
    assert second_rmse_m <= 0.008


def test_an_unreadable_model_is_set_aside_and_the_first_pace_flown(tmp_path: Path) -> None:
    setup = paced_solo(tmp_path)
    path = model_path(setup.show, "uav1")
    path.parent.mkdir(parents=True)
    path.write_text("{not json", encoding="utf-8")
    first, _ = fly(setup, "j1", "一", seed=3)
    assert first["pace_stretch"] == 2.0
    assert path.with_name(path.name + ".bad").read_text(encoding="utf-8") == "{not json"
    assert json.loads(path.read_text(encoding="utf-8"))["format"] == "skyquill.tracking/1"


def test_without_tracking_pace_a_job_flies_as_planned(tmp_path: Path) -> None:
    show = load_show(SHOWS / "solo.yaml")
    storage = show.storage.model_copy(update={"database": tmp_path / "show.sqlite3"})
    setup = vehicle_setup(show.model_copy(update={"storage": storage}), "uav1")
    prepared = prepare_job(setup, JobAssignment(job_id="j1", text="一"))
    assert writing_plan(prepared).pace is None
    assert not model_path(setup.show, "uav1").exists()

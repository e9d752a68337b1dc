"""The live agent records each job in the kinds' trace format (``FlownWriting``): what the backend
reports maps onto it field by field, the metrics, ink and files follow from it, and a flown job
measures exactly as the kinds measure the same flight handed to them directly."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from job_traces import recorded_trace, solo_job

from bus.messages import JobAssignment
from showfile import load_show
from vehicle_agent.jobs import job_metrics, prepare_job, write_job_report, writing_plan
from vehicle_agent.setup import vehicle_setup
from vehicle_agent.written_ink import written_ink
from vehicles.kind import FlownWriting

SHOWS = Path(__file__).resolve().parent.parent / "shows"
N = 6
T = np.linspace(0.0, 0.05, N)
POSITION = np.arange(3 * N, dtype=np.float64).reshape(N, 3) / 7.0
VELOCITY = POSITION[::-1] / 3.0
REFERENCE = POSITION + 0.01
PEN_DOWN = np.array([False, True, True, True, True, False])
CONTACT = np.array([False, True, True, False, True, False])
TIP = POSITION - np.array([0.0, 0.0, 0.25])
WIDTH = np.array([0.01, 0.02, 0.0, 0.03, 0.02, 0.0])  # touching with no width; width in the air


def test_a_backend_that_knows_its_pen_is_recorded_with_tip_base_ink_and_contact() -> None:
    force = np.linspace(0.0, 2.0, N)
    trace = recorded_trace("j1", 2, T, POSITION, VELOCITY, REFERENCE, PEN_DOWN, CONTACT, TIP,
                           WIDTH, force)  # fmt: skip
    flown = trace.flown
    assert (trace.job_id, trace.attempt, trace.pen_known) == ("j1", 2, True)
    assert trace.duration_s == T[-1]
    np.testing.assert_array_equal(flown.t_s, T)
    np.testing.assert_array_equal(flown.reference_m_enu, REFERENCE)
    np.testing.assert_array_equal(flown.writing_point_m_enu, TIP)
    np.testing.assert_array_equal(flown.base_m_enu, POSITION)
    np.testing.assert_array_equal(flown.pen_down, PEN_DOWN)
    np.testing.assert_array_equal(flown.ink_width_m, [0.0, 0.02, 0.0, 0.0, 0.02, 0.0])
    np.testing.assert_array_equal(flown.force_n, force)
    assert set(flown.extra) == {"velocity_mps_enu", "pen_contact"}
    np.testing.assert_array_equal(flown.extra["velocity_mps_enu"], VELOCITY)
    np.testing.assert_array_equal(flown.extra["pen_contact"], CONTACT)
    assert flown.extra["pen_contact"].dtype == np.bool_ and flown.abort_reason is None


def test_without_a_known_pen_the_vehicle_position_is_the_writing_point() -> None:
    for contact in (None, CONTACT):  # contact alone (an ideal vehicle): still no pen
        trace = recorded_trace("j1", 1, T, POSITION, VELOCITY, REFERENCE, PEN_DOWN, contact)
        flown = trace.flown
        assert not trace.pen_known and flown.base_m_enu is None and flown.force_n is None
        np.testing.assert_array_equal(flown.writing_point_m_enu, POSITION)
        np.testing.assert_array_equal(flown.ink_width_m, np.zeros(N))
        assert ("pen_contact" in flown.extra) == (contact is not None)


def test_a_recorded_job_measures_as_its_kind_scores_the_same_flight() -> None:
    """The agent's metrics are the kind's score of the flight as the agent used to hand it over
    (tip as writing point, body as base, ink where touching, velocity and tip as extras): every
    figure and the ink picture equal, to the bit."""
    setup = vehicle_setup(load_show(SHOWS / "solo.yaml"), "uav1")
    prepared = prepare_job(setup, JobAssignment(job_id="j1", text="永"))
    s = prepared.samples
    k = s.t_s.shape[0]
    rng = np.random.default_rng(12)
    position = s.position_m_enu + rng.normal(0.0, 0.003, (k, 3))
    tip = position - np.array([0.0, 0.0, 0.25]) + rng.normal(0.0, 0.001, (k, 3))
    contact = s.pen_down & (rng.random(k) > 0.05)
    width = np.where(rng.random(k) > 0.1, rng.uniform(0.01, 0.03, k), 0.0)
    force = rng.uniform(0.0, 1.0, (k,))
    args = (s.t_s, position, s.velocity_mps_enu, s.position_m_enu, s.pen_down)
    trace = recorded_trace("j1", 1, *args, contact, tip, width, force)
    metrics = job_metrics(setup, prepared, trace)

    by_hand = FlownWriting(
        t_s=s.t_s,
        reference_m_enu=s.position_m_enu,
        writing_point_m_enu=tip,
        pen_down=s.pen_down,
        ink_width_m=np.where(contact, width, 0.0),
        base_m_enu=position,
        force_n=force,
        extra={"velocity_mps_enu": s.velocity_mps_enu, "tip_m_enu": tip},
    )
    score = setup.kind.score(writing_plan(prepared), by_hand, setup.settings)
    assert metrics.iou is not None and 0.0 < metrics.iou < 1.0
    assert (metrics.rmse_pen_down_m, metrics.rmse_m, metrics.max_error_m, metrics.iou) == (
        score.rmse_pen_down_m,
        score.rmse_m,
        score.max_error_m,
        score.iou,
    )
    assert metrics.extra == {name: float(value) for name, value in score.extra.items()}
    assert metrics.duration_s == float(s.t_s[-1] - s.t_s[0])
    ink = written_ink(setup.surface.to_surface(tip), width, contact, setup.writing_area_m)
    assert metrics.written == ink

    body = recorded_trace("j1", 1, *args)  # no pen: the body's errors, no ink
    unknown = job_metrics(setup, prepared, body)
    error = np.linalg.norm(position - s.position_m_enu, axis=1)
    assert unknown.iou is None and unknown.written is None
    assert unknown.rmse_m == float(np.sqrt(np.mean(error**2)))
    assert unknown.rmse_pen_down_m == float(np.sqrt(np.mean(error[s.pen_down] ** 2)))
    assert unknown.max_error_m == float(error.max())


@pytest.mark.parametrize("detail", ["full", "compact"])
def test_flight_npz_holds_the_trace_under_its_field_names(tmp_path: Path, detail: str) -> None:
    setup, prepared = solo_job(tmp_path, detail)
    s = prepared.samples
    tip = s.position_m_enu - np.array([0.0, 0.0, 0.25])
    width = np.where(s.pen_down, 0.02, 0.0)
    args = (s.t_s, s.position_m_enu, s.velocity_mps_enu, s.position_m_enu, s.pen_down)
    trace = recorded_trace("j1", 1, *args, s.pen_down.copy(), tip, width)
    out = write_job_report(setup, prepared, trace, None)
    flown = trace.flown
    with np.load(out / "flight.npz") as flight:
        assert bool(flight["pen_known"])
        own = {"t_s", "reference_m_enu", "writing_point_m_enu", "pen_down", "ink_width_m",
               "base_m_enu", "velocity_mps_enu", "pen_contact", "pen_known"}  # fmt: skip
        if detail == "full":
            assert set(flight) == own
            read = FlownWriting(
                t_s=flight["t_s"],
                reference_m_enu=flight["reference_m_enu"],
                writing_point_m_enu=flight["writing_point_m_enu"],
                pen_down=flight["pen_down"],
                ink_width_m=flight["ink_width_m"],
                base_m_enu=flight["base_m_enu"],
                extra={n: flight[n] for n in ("velocity_mps_enu", "pen_contact")},
            )
            for name in ("t_s", "reference_m_enu", "writing_point_m_enu", "pen_down"):
                np.testing.assert_array_equal(getattr(read, name), getattr(flown, name))
            np.testing.assert_array_equal(read.ink_width_m, flown.ink_width_m)
            np.testing.assert_array_equal(read.base_m_enu, flown.base_m_enu)
            for name, value in flown.extra.items():
                np.testing.assert_array_equal(read.extra[name], value)
        else:  # at 20 Hz, floats in float32, the plan's reference beside
            planned = {"reference_t_s", "reference_position_m_enu", "reference_pen_down"}
            assert set(flight) == own | planned
            kept = np.searchsorted(s.t_s, flight["t_s"] - 1e-9)
            np.testing.assert_allclose(flight["writing_point_m_enu"], tip[kept], atol=1e-4)
            np.testing.assert_array_equal(flight["pen_contact"], s.pen_down[kept])
            assert flight["ink_width_m"].dtype == np.float32

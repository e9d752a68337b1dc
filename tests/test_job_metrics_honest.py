"""A show job reports only what it measured (issue 34): a job flown in part is scored against the
whole character and says it was partial; a job whose pen never came down has no pen-down RMSE
(None, null on the wire) and can never be ``done``, whatever the show's bounds.

The flights are closed loops: the agent's job runner and the in-process sim backend of the
Airshow show (``tests/live_kinds.py``). An abort at 30 % is the trace of the whole flight cut at
30 % of the plan (the closed loop up to then is what it was; what the runner does after an abort
is tested in tests/test_safety_runner.py)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import msgspec
import numpy as np
import pytest
from live_kinds import LiveRun

from bus.messages import JobAssignment, JobMetrics
from showfile import parse_show
from vehicle_agent.jobs import job_metrics
from vehicle_agent.runner_io import PreparedJob, result_report
from vehicle_agent.trace import JobTrace
from vehicles.verdict import WritingBounds, writing_verdict

AIRSHOW = Path(__file__).resolve().parents[1] / "shows" / "airshow-2014.yaml"


@pytest.fixture(scope="module")
def flown_job() -> tuple[LiveRun, PreparedJob, JobTrace]:
    """十 written to its end by uav1 of the Airshow show, closed loop."""
    run = LiveRun(parse_show(AIRSHOW.read_text(encoding="utf-8")), "uav1")
    assert run.assign(JobAssignment(job_id="j1", text="十", attempt=1))
    run.until_back(120.0)
    (trace,) = run.finished
    return run, run.prepared["j1"], trace


def _cut(trace: JobTrace, fraction: float, duration_s: float) -> JobTrace:
    """``trace`` up to ``fraction`` of the plan's duration: what an abort there leaves."""
    flown = trace.flown
    keep = flown.t_s <= fraction * duration_s
    extra = {name: value[keep] for name, value in flown.extra.items()}
    cut = replace(
        flown,
        t_s=flown.t_s[keep],
        reference_m_enu=flown.reference_m_enu[keep],
        writing_point_m_enu=flown.writing_point_m_enu[keep],
        pen_down=flown.pen_down[keep],
        ink_width_m=flown.ink_width_m[keep],
        base_m_enu=None if flown.base_m_enu is None else flown.base_m_enu[keep],
        force_n=None if flown.force_n is None else flown.force_n[keep],
        extra=extra,
    )
    return replace(trace, flown=cut)


@pytest.mark.slow
def test_a_job_aborted_at_30_percent_scores_against_the_whole_character(
    flown_job: tuple[LiveRun, PreparedJob, JobTrace],
) -> None:
    run, prepared, trace = flown_job
    whole = job_metrics(run.setup, prepared, trace)
    assert whole.flown_fraction == 1.0 and whole.iou is not None and whole.iou > 0.6
    part = job_metrics(run.setup, prepared, _cut(trace, 0.3, prepared.samples.duration_s))
    assert part.flown_fraction == pytest.approx(0.3, abs=0.01)
    # today's code scored the part against the part of the target it flew: IoU as high as whole
    assert part.iou is not None and part.iou < 0.5 * whole.iou, (part.iou, whole.iou)
    assert part.rmse_pen_down_m is not None  # the errors of what was flown stay measured
    report = result_report("uav1", trace, part, run.setup.runner_config.safety.writing)
    assert report.event == "failed" and report.error is not None
    assert "written in part: 30% of the plan flown" in report.error.message


@pytest.mark.slow
def test_a_job_whose_pen_never_came_down_is_not_measured_and_never_done(
    flown_job: tuple[LiveRun, PreparedJob, JobTrace],
) -> None:
    run, prepared, trace = flown_job
    flown = trace.flown
    lifted = replace(  # the plan flown with the brush held up: no pen-down tick, no ink
        trace,
        flown=replace(
            flown,
            pen_down=np.zeros_like(flown.pen_down),
            ink_width_m=np.zeros_like(flown.ink_width_m),
            extra={**flown.extra, "pen_contact": np.zeros_like(flown.pen_down)},
        ),
    )
    metrics = job_metrics(run.setup, prepared, lifted)
    assert metrics.rmse_pen_down_m is None  # today: 0.0, a perfect score of nothing
    assert metrics.iou == 0.0
    assert not any("pen_down" in name for name in metrics.extra), metrics.extra
    wire = msgspec.json.decode(msgspec.json.encode(metrics), type=JobMetrics)
    assert wire.rmse_pen_down_m is None  # "not measured" said on the wire, read back
    loose = WritingBounds(rmse_pen_down_max_m=1.0, iou_min=0.0)  # bounds that let anything by
    report = result_report("uav1", lifted, metrics, loose)
    assert report.event == "failed" and report.error is not None
    assert report.error.code == "writing_bounds" and "nothing written" in report.error.message


def test_the_verdict_never_passes_what_was_not_written() -> None:
    loose = WritingBounds(rmse_pen_down_max_m=1.0, iou_min=0.0)
    assert writing_verdict(0.001, 0.9, loose) is None
    assert writing_verdict(0.001, None, loose) is None  # a backend without a brush model
    assert writing_verdict(None, None, loose) == "nothing written: the pen never came down"
    assert writing_verdict(0.001, 0.0, loose) == "no ink on the target (IoU 0)"
    partial = writing_verdict(0.001, 0.9, loose, flown_fraction=0.3)
    assert partial == "written in part: 30% of the plan flown"
    assert writing_verdict(float("nan"), 0.9, loose) is not None

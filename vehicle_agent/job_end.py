"""The end of a flown job in the agent: its metrics measured, its files kept and its report made,
whether it was flown to its end or broken off after its writing began, whatever broke it off
(off the control loop, in the job work)."""

from __future__ import annotations

import logging

import msgspec

from bus.messages import AgentReport, JobMetrics
from vehicle_agent.end_reasons import ended_report, flown_fraction, pen_came_down
from vehicle_agent.runner_io import AbortedJob, PreparedJob, result_report
from vehicle_agent.trace import JobTrace
from vehicle_agent.work import JobWork
from vehicles.verdict import WritingBounds

log = logging.getLogger(__name__)


async def measured_and_kept(
    work: JobWork, prepared: PreparedJob, trace: JobTrace, vehicle_id: str
) -> JobMetrics | None:
    """Measure ``trace`` against the whole plan, then record the job's files (``metrics.json``,
    ``flight.npz``, its picture: ``vehicle_agent/jobs.py``); None when it could not be measured
    (said in the log, as a failure to record is: the result is reported all the same)."""
    metrics = None
    try:
        metrics = await work.measure(prepared, trace)
    except Exception:  # reported as unmeasured: done means within the writing bounds
        log.exception("%s: metrics of %s failed", vehicle_id, trace.job_id)
    try:
        where = await work.archive(prepared, trace, metrics)
    except Exception:
        log.exception("%s: cannot record job %s", vehicle_id, trace.job_id)
    else:
        if where is not None:
            log.info("%s: job %s recorded in %s", vehicle_id, trace.job_id, where)
    return metrics


def job_result(
    vehicle_id: str,
    prepared: PreparedJob,
    trace: JobTrace,
    metrics: JobMetrics | None,
    bounds: WritingBounds,
    aborted: AbortedJob | None,
) -> AgentReport:
    """The report of a measured job: flown to its end (``aborted`` None), ``done`` or
    ``failed`` as its metrics meet ``bounds`` (:func:`result_report`); broken off by a safety
    abort after its writing began, its ``failed`` report with the metrics of what was flown
    (None: unmeasured); broken off by anything else (a cancel, a land, an emergency stop, a
    fault, its lease: the trace's ``abort_reason``), its ``ended`` report, which tells the
    orchestrator what was written and decides nothing (:func:`ended_report`)."""
    if aborted is None:
        return result_report(vehicle_id, trace, metrics, bounds)
    if aborted.report is not None:
        return msgspec.structs.replace(aborted.report, metrics=metrics)
    fraction = flown_fraction(prepared, trace) if metrics is None else metrics.flown_fraction
    reason = trace.flown.abort_reason or "broken_off"
    down = pen_came_down(trace)
    return ended_report(vehicle_id, trace.job_id, reason, fraction, metrics, pen_came_down=down)

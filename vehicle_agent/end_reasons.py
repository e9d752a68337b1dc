"""How a job that did not end by being written whole ended, in words (pure): the reason codes the
job runner gives a job it breaks off (``FlownWriting.abort_reason``), the sentence its picture
title and ``metrics.json`` say, and the ``ended`` report that tells the orchestrator what was
written of a job stopped by something other than a safety abort.

A safety abort has its ``failed`` report (``vehicle_agent/runner_job.py``); every other end (an
operator's cancel or land, an emergency stop, a vehicle fault, the job given up on its lease)
leaves the decision to the orchestrator, which asked for it or learns it from the vehicle's
status: the ``ended`` report only says what was written, and changes nothing of the job
(``orchestrator/job_ends.py``).
"""

from __future__ import annotations

import numpy as np

from bus.messages import AgentReport, ErrorInfo, JobMetrics
from vehicle_agent.runner_io import PreparedJob
from vehicle_agent.trace import PEN_CONTACT, JobTrace

GIVEN_UP = "given_up"
"""The reason of a job given up on its lease (``vehicle_agent/job_guard.py``)."""

SENTENCES = {
    "cancelled": "cancelled",
    "landed_by_operator": "landed on the operator's command",
    "estop": "stopped by an emergency stop",
    "vehicle_fault": "ended by a vehicle fault",
    GIVEN_UP: "given up on its lease",
    "deviation": "aborted for deviation",
    "geofence": "aborted at its geofence",
}
"""Each reason the runner gives a job broken off after its writing began, as said to people.
``cancelled`` does not say by whom: the agent gets the same ``cancel`` from an operator and from
the orchestrator (the job written elsewhere, its phrase sent back); the show's log says who (the
operator's own line)."""


def flown_fraction(prepared: PreparedJob, trace: JobTrace) -> float:
    """Fraction 0..1 of the plan flown: the trace's last tick (writing time from the start of
    the plan, as :class:`vehicle_agent.runner_job.RunningJob` records it) over the plan's
    duration; 1 for a plan of no duration."""
    duration_s = prepared.samples.duration_s
    t_s = trace.flown.t_s
    if duration_s <= 0.0:
        return 1.0
    if not t_s.size:
        return 0.0
    return float(np.clip(t_s[-1] / duration_s, 0.0, 1.0))


def pen_came_down(trace: JobTrace) -> bool:
    """Whether the pen touched at some tick of ``trace``: its contact where the backend reports
    it, else the reference's pen state (all an autopilot without a brush model tells)."""
    flown = trace.flown
    contact = flown.extra.get(PEN_CONTACT)
    return bool(np.any(contact if contact is not None else flown.pen_down))


def end_sentence(reason: str, flown_fraction: float, *, pen_came_down: bool) -> str:
    """``cancelled at 40% of its plan``; ``, its pen never down: nothing written`` when the pen
    never touched; an unknown reason as ``broken off (<reason>)``."""
    said = SENTENCES.get(reason, f"broken off ({reason})")
    sentence = f"{said} at {flown_fraction:.0%} of its plan"
    if not pen_came_down:
        sentence += ", its pen never down: nothing written"
    return sentence


def how_it_ended(prepared: PreparedJob, trace: JobTrace) -> str | None:
    """:func:`end_sentence` of a job broken off (its trace's ``abort_reason``); None for a job
    flown to its end."""
    reason = trace.flown.abort_reason
    if reason is None:
        return None
    fraction = flown_fraction(prepared, trace)
    return end_sentence(reason, fraction, pen_came_down=pen_came_down(trace))


def ended_report(
    vehicle_id: str,
    job_id: str,
    reason: str,
    flown_fraction: float,
    metrics: JobMetrics | None,
    *,
    pen_came_down: bool,
) -> AgentReport:
    """The ``ended`` report of a job broken off for ``reason`` (not a safety abort): ``progress``
    the fraction of its plan flown, ``metrics`` what was written scored against the whole
    character (None: not measured, or nothing flown), ``error`` the reason and its sentence."""
    sentence = end_sentence(reason, flown_fraction, pen_came_down=pen_came_down)
    return AgentReport(
        vehicle_id=vehicle_id,
        job_id=job_id,
        event="ended",
        progress=min(max(flown_fraction, 0.0), 1.0),
        metrics=metrics,
        error=ErrorInfo(code=reason, message=sentence),
    )

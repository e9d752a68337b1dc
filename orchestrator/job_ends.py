"""``ended`` reports (pure): what a vehicle wrote of a job stopped by something other than its own
result or a safety abort, told after the fact and deciding nothing.

A job ends on its vehicle by an operator's ``cancel`` (or the orchestrator's: the job written
elsewhere, its phrase sent back), a ``land``/``land_all``, an ``estop``, a vehicle fault, or the
job given up on its lease (``vehicle_agent/end_reasons.py``). The orchestrator decides each of
these on its own account, before or after the report: a cancel makes the job ``cancelled``
(``orchestrator/operator.py``); a land or an emergency stop puts it back in the queue
(``orchestrator/requeue.py``); a vehicle in fault, or one whose status no longer names the job,
hands it back (``orchestrator/presence.py``). The report changes none of that: no state, no
progress, no board or sheet, no command to any vehicle, whoever holds the job by now. It gives the
show's log a line of what was written (rate-limited with the vehicle's own events, since the
vehicle's key is all that vouches for it), and a cancelled job that its vehicle was writing
keeps the metrics of what was written (its ink picture left out: the sheet's is the next
writer's business), so that the console and the records show how far it got.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from bus.messages import AgentReport, CommandReply
from orchestrator.core_types import Effects
from orchestrator.jobs import Job, update
from orchestrator.written import split_written

if TYPE_CHECKING:
    from orchestrator.book_protocol import BookProtocol

MAX_REASON_CHARS = 40
"""An agent's reason code is cut to this many characters in the log line."""


def apply_ended(
    book: BookProtocol, job: Job, rep: AgentReport, eff: Effects, now_s: float
) -> CommandReply:
    """Record what ``rep`` (an ``ended`` report) says was written of ``job``; acknowledged
    whatever it says, so that the agent does not send it again."""
    view = book.vehicles.get(rep.vehicle_id)
    if view is not None and view.may_log(now_s):
        line = ended_line(job.label, rep)
        book.event(
            eff, now_s, "info", "job_ended", line, vehicle_id=rep.vehicle_id, job_id=job.job_id
        )
    held_by_it = rep.vehicle_id == job.vehicle_id
    if held_by_it and job.state == "cancelled" and job.metrics is None and rep.metrics is not None:
        metrics, _ = split_written(rep.metrics)
        book.put(eff, update(job, now_s, metrics=metrics))
    return CommandReply(ok=True, message="noted what was written; nothing else changes")


def ended_line(label: str, rep: AgentReport) -> str:
    """``十: uav1 stopped it (cancelled) at 40% of its plan, IoU 0.21``, from the report's
    figures (never from its words)."""
    reason = (rep.error.code if rep.error is not None else "ended")[:MAX_REASON_CHARS]
    m = rep.metrics
    if m is None and rep.progress <= 0.0:
        what = "before its writing began: nothing written"
    elif m is None:
        what = f"at {rep.progress:.0%} of its plan, not measured"
    elif m.rmse_pen_down_m is None:
        what = f"at {m.flown_fraction:.0%} of its plan, its pen never down: nothing written"
    else:
        iou = "" if m.iou is None else f", IoU {m.iou:.2f}"
        what = f"at {m.flown_fraction:.0%} of its plan{iou}"
    return f"{label}: {rep.vehicle_id} stopped it ({reason}) {what}"

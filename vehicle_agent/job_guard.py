"""The job lease (:mod:`vehicle_agent.lease`) applied to the job the runner flies.

Before each tick the service asks :meth:`JobGuard.before_tick`: a job that may have been given to
another vehicle by now (this agent stalled, or its writing went unacknowledged) is given up at
once, brush lifted, back home (:meth:`JobGuard.give_up`, also what the report outbox calls when the
orchestrator answers ``not_assigned``); a vehicle waiting at the start of its writing sends a
*ready* report (``holding`` with the planned writing: the brush goes down only once one is
acknowledged); a flown job unacknowledged for a while gets a report that asks the orchestrator
to confirm it, which the service queues.
"""

from __future__ import annotations

import logging

from bus.messages import AgentReport
from vehicle_agent.events import EventOutbox
from vehicle_agent.job_runner import JobRunner
from vehicle_agent.lease import JobLease
from vehicle_agent.runner_io import ACTIVE_PHASES

log = logging.getLogger(__name__)


class JobGuard:
    """Holds ``runner``'s job to ``lease``; says what it gave up in ``events``."""

    def __init__(
        self,
        lease: JobLease,
        runner: JobRunner,
        events: EventOutbox,
        vehicle_id: str,
    ) -> None:
        self.lease = lease
        self.runner = runner
        self.events = events
        self.vehicle_id = vehicle_id

    def before_tick(self, wall_s: float, stalled_s: float, progress: float) -> AgentReport | None:
        """Give the job up if it may be someone else's by now; the report asking the orchestrator
        to confirm the job when it has gone unacknowledged for a while, else None. ``wall_s``:
        wall (monotonic) time in [s]; ``stalled_s``: the longest stall in [s] seen since the last
        tick; ``progress``: the job's latest progress (0..1)."""
        lease, runner = self.lease, self.runner
        gap_s = max(lease.tick(wall_s), stalled_s)
        writing = runner.phase == "write"
        lease.hold(
            runner.job_id, active=runner.phase in ACTIVE_PHASES, writing=writing, now_s=wall_s
        )
        why = lease.breach(gap_s, wall_s)
        ready_writing_s = runner.ready_to_write_s
        if why is not None:
            self.give_up(why)
        elif lease.job_id is None:
            return None
        elif ready_writing_s is not None and lease.ready_due(wall_s):
            return AgentReport(
                vehicle_id=self.vehicle_id,
                job_id=lease.job_id,
                event="holding",
                planned_duration_s=ready_writing_s,
            )
        elif lease.probe_due(wall_s):
            return AgentReport(
                vehicle_id=self.vehicle_id,
                job_id=lease.job_id,
                event="progress" if writing else "holding",
                progress=progress if writing else 0.0,
            )
        return None

    def give_up(self, why: str) -> None:
        """Stop the job at once (brush up, home): the orchestrator requeues it, or did already."""
        runner, job_id = self.runner, self.runner.job_id
        if job_id is None or runner.phase not in ACTIVE_PHASES:
            return
        runner.give_up()
        runner.message = f"gave {job_id} up ({why}): brush lifted, returning"
        log.warning("%s: gave job %s up: %s", self.vehicle_id, job_id, why)
        message = f"{self.vehicle_id} gave job {job_id} up: {why}"
        self.events.push("warning", "job_given_up", message, job_id=job_id)

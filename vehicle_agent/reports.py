"""The agent's reports to the orchestrator: a FIFO sent to its ``report`` queryable, each retried
until some reply acknowledges it (``progress`` and ``holding`` reports are best effort and
superseded by newer ones). Once a result (``done``/``failed``) is answered, ``settled`` is told
(the agent's :class:`vehicle_agent.results.ResultJournal` lets it go). An acknowledgement
renews the job lease; a ``not_assigned`` answer about the running job makes the agent give it
up. Neither follows an ``ended`` report: its job is over for this vehicle, which may hold it
again by now."""

from __future__ import annotations

import asyncio
import logging
import time
from collections import deque
from collections.abc import Callable

from bus.keys import ShowKeys
from bus.messages import AgentReport, CommandReply
from bus.rpc import NoReplyError, RemoteError, aquery_one
from bus.session import Session
from vehicle_agent.lease import JobLease

log = logging.getLogger(__name__)

RETRY_CODES = frozenset({"internal", "unavailable", "busy"})
"""Error replies to a report after which it is sent again: the orchestrator could not take it.
An error reply that is not the orchestrator's at all (Zenoh's own "Timeout" from a router whose
query outlived a link just healed) is no answer (``bus.rpc.NOT_THE_SERVICES``): taken as one, it
settled a ``done`` the orchestrator never stored, the agent stopped naming the job, the
orchestrator gave it to another vehicle, and a character was written twice (a fresh clone's CI,
``test_multihost_show``)."""
BEST_EFFORT = frozenset({"progress", "holding"})
"""Reports sent once, and superseded by a newer report of the same job not yet sent."""
PHRASE_WAITS = "phrase_waits"
"""The answer to a *ready* report while the other characters of its phrase are not all ready
(``orchestrator/phrases.py``): the vehicle holds at the start and asks again, no fault."""
RESULTS = frozenset({"done", "failed"})
"""Reports that end a job: ``settled`` is called once the orchestrator has answered one."""


class ReportOutbox:
    """Reports of one vehicle waiting for the orchestrator's receipt; ``await send_forever()``."""

    def __init__(
        self,
        keys: ShowKeys,
        vehicle_id: str,
        lease: JobLease,
        *,
        retry_s: float,
        timeout_s: float,
        running_job: Callable[[], str | None],
        refused: Callable[[str], None],
        settled: Callable[[str], None],
    ) -> None:
        self.keys = keys
        self.vehicle_id = vehicle_id
        self._lease = lease
        self._retry_s = retry_s
        self._timeout_s = timeout_s
        self._running_job = running_job
        self._refused = refused
        self._settled = settled
        self._reports: deque[AgentReport] = deque()
        self._ready = asyncio.Event()

    def queue(self, report: AgentReport) -> None:
        """Send ``report`` after those queued before it."""
        last = self._reports[-1] if self._reports else None
        if last is not None and last.event in BEST_EFFORT and last.job_id == report.job_id:
            self._reports.pop()  # a newer report supersedes a progress not yet sent
        self._reports.append(report)
        self._ready.set()

    async def send_forever(self, session: Session) -> None:
        """Deliver the queued reports in order, as they come."""
        while True:
            await self._ready.wait()
            while self._reports:
                report = self._reports[0]
                delivered = await self._deliver(session, report)
                if delivered and report.event in RESULTS:
                    self._settled(report.job_id)
                if delivered or report.event in BEST_EFFORT:
                    if self._reports and self._reports[0] is report:
                        self._reports.popleft()
                else:
                    await asyncio.sleep(self._retry_s)
            self._ready.clear()

    async def _deliver(self, session: Session, report: AgentReport) -> bool:
        sent_at_s = time.monotonic()
        vid = self.vehicle_id
        try:
            reply = await aquery_one(
                session, self.keys.report(vid), report, CommandReply, timeout_s=self._timeout_s
            )
        except NoReplyError:
            return False
        except RemoteError as exc:
            if exc.info.code in RETRY_CODES:
                return False
            log.warning("%s: report %s refused: %s", vid, report.event, exc)
            return True  # the orchestrator answered: it has seen the report
        except Exception as exc:
            log.warning("%s: report %s refused: %s", vid, report.event, exc)
            return True  # the orchestrator answered: it has seen the report
        if report.event == "ended":  # over for this vehicle: no lease to renew, none to give up
            if not reply.ok:
                log.warning("%s: report ended not accepted: %s", vid, reply.message)
            return True
        if reply.ok:
            ready = report.planned_duration_s if report.event == "holding" else None
            self._lease.acknowledged(report.job_id, sent_at_s, ready)
        elif reply.error is not None and reply.error.code == PHRASE_WAITS:
            # the answer every ready period while its phrase's other vehicles get ready
            log.debug("%s: %s holds for its phrase: %s", vid, report.job_id, reply.message)
        else:
            log.warning("%s: report %s not accepted: %s", vid, report.event, reply.message)
            refused = reply.error is not None and reply.error.code == "not_assigned"
            if refused and report.job_id == self._running_job():
                self._refused("the orchestrator says it is not this vehicle's any more")
        return True

"""A vehicle's job results not yet heard by the orchestrator, kept on disk until it acknowledges
them, so that a character written in full is never given to another vehicle.

The orchestrator keeps a job whose vehicle may have written it from everyone else until that
vehicle says how it ended (``orchestrator/holders.py``); this journal lets the vehicle say it
after a restart too. From the control tick in which the writing ended (before anything slow:
measuring, recording) a file holds the job's result: first ``failed`` with code ``unmeasured``
(written, not yet measured: ``done`` means measured within the writing bounds), then the
measured result. A job broken off by a safety abort after its writing began is kept the same
way: from the tick of the abort its ``failed`` report, then that report with the metrics of
what was flown (``vehicle_agent/job_end.py``). The file goes when the orchestrator has answered
the result. An agent starting anew sends what it finds, and its status names that job
meanwhile, as the running agent's does.

A file replaced atomically, without fsync, survives the death of the process (SIGKILL, a crash),
which is what a restart follows; not the host's power failing. A kill between the last ink and
the first file (within one control tick) is a kill while writing: the job is written elsewhere and
the board marked half-written.
"""

from __future__ import annotations

import hashlib
import logging
import os
import re
from pathlib import Path

import msgspec

from bus.messages import AgentReport, ErrorInfo

log = logging.getLogger(__name__)

SAFE_NAME = re.compile(r"[A-Za-z0-9_.-]{1,64}")
"""Job ids used as file names as they are (others: their hash; ids come over the network)."""
UNMEASURED_MESSAGE = "written in full, but not measured: its agent stopped before measuring it"


class ResultJournal:
    """The results of one vehicle's finished jobs until the orchestrator has them; ``directory``
    None keeps them in memory only (tests, benches: a restart there is a new journal)."""

    def __init__(self, vehicle_id: str, directory: Path | None) -> None:
        self.vehicle_id = vehicle_id
        self.directory = directory
        self._unsettled: dict[str, AgentReport] = {}

    def written(self, job_id: str, planned_duration_s: float) -> None:
        """``job_id`` has just been written in full (call in the tick its writing ended)."""
        info = ErrorInfo(code="unmeasured", message=UNMEASURED_MESSAGE)
        unmeasured = AgentReport(
            vehicle_id=self.vehicle_id,
            job_id=job_id,
            event="failed",
            progress=1.0,
            planned_duration_s=planned_duration_s,
            error=info,
        )
        self._keep(unmeasured)

    def measured(self, result: AgentReport) -> None:
        """The job's result as it will be reported (``done`` or ``failed``; an aborted job's
        ``failed``, with or without its metrics yet)."""
        self._keep(result)

    def settled(self, job_id: str) -> None:
        """The orchestrator has answered the job's result: nothing to keep any more."""
        if self._unsettled.pop(job_id, None) is None or self.directory is None:
            return
        try:
            self._path(job_id).unlink(missing_ok=True)
        except OSError as exc:  # sent again after a restart: the orchestrator ignores it then
            log.warning("%s: cannot remove the result of %s: %s", self.vehicle_id, job_id, exc)

    def pending(self) -> str | None:
        """A job whose result the orchestrator has not answered yet (the oldest)."""
        return next(iter(self._unsettled), None)

    def unsettled(self, job_id: str) -> bool:
        """Whether ``job_id`` was written here and its result is not yet answered."""
        return job_id in self._unsettled

    def recover(self) -> list[AgentReport]:
        """The results a previous run of this agent left unanswered, oldest first (and kept)."""
        if self.directory is None or not self.directory.is_dir():
            return []
        found: list[tuple[float, AgentReport]] = []
        for path in self.directory.glob("*.json"):
            try:
                report = msgspec.json.decode(path.read_bytes(), type=AgentReport)
                found.append((path.stat().st_mtime, report))
            except (OSError, msgspec.DecodeError) as exc:
                log.warning("%s: unreadable result %s: %s", self.vehicle_id, path.name, exc)
        recovered = [report for _, report in sorted(found, key=lambda pair: pair[0])]
        for report in recovered:
            self._unsettled[report.job_id] = report
        return recovered

    def _keep(self, report: AgentReport) -> None:
        self._unsettled[report.job_id] = report
        if self.directory is None:
            return
        path = self._path(report.job_id)
        partial = path.with_suffix(".part")
        try:
            self.directory.mkdir(parents=True, exist_ok=True)
            partial.write_bytes(msgspec.json.encode(report))
            os.replace(partial, path)
        except OSError as exc:  # the running agent still reports it; only a restart forgets
            log.warning("%s: cannot keep the result of %s: %s", self.vehicle_id, report.job_id, exc)

    def _path(self, job_id: str) -> Path:
        assert self.directory is not None
        safe = SAFE_NAME.fullmatch(job_id)
        name = job_id if safe else hashlib.sha256(job_id.encode()).hexdigest()
        return self.directory / f"{name}.json"

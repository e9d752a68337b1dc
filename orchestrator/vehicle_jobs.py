"""The Book's jobs by vehicle (pure): the one each vehicle holds, the one that waits for it."""

from __future__ import annotations

from dataclasses import dataclass, field

from orchestrator.jobs import Job


@dataclass
class VehicleJobs:
    """Which job each vehicle holds, and which queued job waits for each; :meth:`hold` keeps
    it true as every new version of a job is held."""

    active: dict[str, str] = field(default_factory=dict)
    """Vehicle id -> id of its active job: every status, snapshot and assignment asks,
    and scanning every job held (up to ``MAX_FINAL_JOBS`` finished) per vehicle cost ~50 ms
    of CPU per status at 250 vehicles (``benchmarks/bench_heartbeat.py``)."""
    awaited: dict[str, str] = field(default_factory=dict)
    """Vehicle id -> id of the queued job that waits for it (``orchestrator/holders.py``)."""

    def hold(self, previous: Job | None, job: Job) -> None:
        """Index ``job``, replacing ``previous``, its older version (None: a new job)."""
        was = previous.vehicle_id if previous is not None and previous.active else None
        if was is not None and self.active.get(was) == job.job_id:
            del self.active[was]
        if job.active and job.vehicle_id is not None:
            self.active[job.vehicle_id] = job.job_id
        held_for = previous.vehicle_id if previous is not None else None
        if held_for is not None and self.awaited.get(held_for) == job.job_id:
            del self.awaited[held_for]
        if job.state == "queued" and job.holder_hold_until_s is not None and job.vehicle_id:
            self.awaited[job.vehicle_id] = job.job_id

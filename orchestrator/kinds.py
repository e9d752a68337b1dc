"""Which vehicle kind may take a job, and how long it would write it (pure, in memory).

A kind whose planner refused a job (``plan_failed``, or the orchestrator's own planning of the
job for its ETA) never gets it again; while a vehicle of another kind may still write it, the job
waits for one. Planned durations differ between kinds (a ground writer's metres-tall character
against a brush's), so each kind's is kept for the ETAs while the job waits. Neither outlives the
orchestrator: after a restart a refusing kind may be tried once more and ETAs fall back on the
job's own estimate.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field

from orchestrator.fleet import VehicleInfo, writing_s
from orchestrator.jobs import Job


@dataclass(frozen=True)
class KindPlans:
    """A glyph planned by the vehicle standing for each kind of a show (its first in board
    order, ``vehicles.jobs.kind_writers``, as the kiosk's preview;
    ``orchestrator.submissions.planned_durations_s``)."""

    durations_s: dict[str, float]
    """Planned duration in [s] by kind (a job takes as long as the kind that writes it)."""
    refused: frozenset[str] = frozenset()
    """Kinds whose planner refused the glyph."""

    @property
    def known(self) -> bool:
        """Some kind planned or refused it (else: not planned, the rough estimate stays)."""
        return bool(self.durations_s or self.refused)


@dataclass
class KindMatch:
    """Jobs refused by kinds, and planned durations by kind, of the jobs still waiting."""

    kinds: Mapping[str, str]
    """Vehicle id -> its kind."""
    refused: dict[str, set[str]] = field(default_factory=dict)
    """Job id -> the kinds whose planner refused it."""
    estimates: dict[str, dict[str, float]] = field(default_factory=dict)
    """Job id -> its planned duration in [s] by kind."""

    def may_take(self, job: Job, vehicle_id: str) -> bool:
        """The vehicle's kind has not refused to plan ``job`` (it writes it, as far as known)."""
        refused = self.refused.get(job.job_id)
        return refused is None or self.kinds[vehicle_id] not in refused

    def writing_s_on(self, job: Job, vehicle_id: str) -> float:
        """Sim seconds ``job`` would write on ``vehicle_id`` (its kind's plan if known)."""
        return self.estimates.get(job.job_id, {}).get(self.kinds[vehicle_id]) or writing_s(job)

    def refuse(self, job_id: str, vehicle_id: str, vehicles: Iterable[VehicleInfo]) -> bool:
        """Record that ``vehicle_id``'s kind cannot plan the job; True while a vehicle of another
        kind that has not refused it may still write it."""
        refused = self.refused.setdefault(job_id, set())
        refused.add(self.kinds[vehicle_id])
        return _writable(refused, vehicles)

    def refuse_kinds(
        self, job_id: str, kinds: Iterable[str], vehicles: Sequence[VehicleInfo]
    ) -> None:
        """Record kinds whose planner refused the job before any of them was sent it (the ETA
        planning), as long as a vehicle of another kind may still write it; otherwise leave the
        job to its vehicle, whose refusal fails it with the planner's reason."""
        refused = self.refused.get(job_id, set()) | set(kinds)
        if _writable(refused, vehicles):
            self.refused[job_id] = refused

    def forget(self, job: Job) -> None:
        """Drop what is no longer needed: estimates once it writes, everything once final."""
        if job.final:
            self.refused.pop(job.job_id, None)
        if job.final or job.state == "writing":
            self.estimates.pop(job.job_id, None)


def _writable(refused: set[str], vehicles: Iterable[VehicleInfo]) -> bool:
    """A vehicle of a kind not in ``refused`` may write the job."""
    return any(v.kind not in refused and v.cannot_write is None for v in vehicles)

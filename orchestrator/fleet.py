"""The orchestrator's view of the vehicles, and queue ETAs (pure)."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

from bus.messages import VehicleStateName, VehicleSummary
from orchestrator.jobs import Job

READY_STATES: frozenset[str] = frozenset({"idle", "landed"})
"""Vehicle states in which a vehicle may take a new job."""


@dataclass(frozen=True)
class VehicleInfo:
    """A vehicle as the show file declares it."""

    vehicle_id: str
    """Vehicle id."""
    kind: str
    """Vehicle kind, e.g. ``quadrotor-brush``."""
    board_id: str
    """The board it writes on."""


@dataclass
class VehicleView:
    """What the orchestrator currently knows about one vehicle (mutable, owned by the Book)."""

    info: VehicleInfo
    """Declaration from the show file."""
    alive: bool = False
    """Its liveliness token is present (not enough to be taken as present: see ``heard_at_s``)."""
    state: VehicleStateName = "lost"
    """Last state the vehicle reported."""
    lost: bool = True
    """Token gone, or silent, for ``lost_after_s`` (or never heard): shown as ``lost``."""
    reported_job_id: str | None = None
    """Job the vehicle last said it works on."""
    status_at_s: float | None = None
    """Orchestrator time of its last status, [s]."""
    last_seen_s: float | None = None
    """Orchestrator time of its last status, telemetry or liveliness change, [s]."""
    gone_since_s: float | None = None
    """Orchestrator time its token disappeared (or the orchestrator started), [s]."""
    heard_at_s: float | None = None
    """Orchestrator time of the last message it sent itself (status or telemetry, on its own
    keys), [s]: the heartbeat; a token alone (which anyone may fake) keeps no vehicle present."""
    token_at_s: float | None = None
    """Orchestrator time its token last appeared, [s] (its first status is due from then)."""
    checked_at_s: float | None = None
    """Orchestrator time its presence was last checked, [s]; a long gap means the orchestrator
    itself stalled, and heartbeats that queued up meanwhile are waited for once."""
    resumed_at_s: float | None = None
    """Orchestrator time it last resumed after such a stall, [s]."""
    was_seen: bool = False
    """It has been alive at least once since the orchestrator started."""
    paused: bool = False
    """The operator stopped giving it jobs (pause, land, estop)."""
    held: bool = False
    """Landed or stopped by the operator: no job until an explicit ``release`` (not ``resume``)."""
    refused_until_s: float = 0.0
    """No new assignment before this time, [s] (after a refused or unanswered assignment)."""
    mismatch_since_s: float | None = None
    """Since when its status has not mentioned the job the orchestrator gave it, [s]."""
    message: str = "not connected"
    """Human note for displays."""
    last_alert_s: float = -1e18
    """Orchestrator time of its last tracking alert, [s]."""
    event_tokens: float = 10.0
    """Events of this vehicle that may still be relayed into the log at once (token bucket)."""
    event_tokens_at_s: float | None = None
    """Orchestrator time ``event_tokens`` was last refilled, [s]."""

    def summary(self, job_id: str | None) -> VehicleSummary:
        """The wire view of this vehicle."""
        return VehicleSummary(
            vehicle_id=self.info.vehicle_id,
            kind=self.info.kind,
            state="lost" if self.lost else self.state,
            alive=self.alive,
            board_id=self.info.board_id,
            job_id=job_id,
            last_seen_s=self.last_seen_s,
            message=self.message + (" (paused)" if self.paused and not self.held else ""),
            held=self.held,
        )


def ready_for_job(view: VehicleView, now_s: float) -> bool:
    """Healthy and idle by its own account, not paused, not backing off."""
    return (
        view.alive
        and not view.lost
        and not view.paused
        and not view.held
        and view.status_at_s is not None
        and view.state in READY_STATES
        and view.reported_job_id is None
        and view.refused_until_s <= now_s
    )


@dataclass(frozen=True)
class EtaModel:
    """Timing assumptions of the ETA estimate."""

    time_scale: float = 1.0
    """Simulated seconds per wall-clock second (the show's ``time_scale``)."""
    overhead_s: float = 10.0
    """Sim time per job besides writing: take-off, transit, return and landing, [s]."""


def remaining_s(job: Job) -> float:
    """Sim seconds of writing left in an active job."""
    duration = job.planned_duration_s or job.estimate_s
    return max(0.0, duration * (1.0 - job.progress))


def queue_etas(
    queue: Sequence[Job],
    active_by_vehicle: Mapping[str, Job],
    usable_vehicles: Iterable[str],
    now_s: float,
    model: EtaModel,
) -> dict[str, float]:
    """Seconds from now until each queued job should start writing (list scheduling).

    Every usable vehicle takes the next job as soon as it is free (jobs in queue order). Vehicles
    sharing a board are treated as independent (optimistic). Empty when no vehicle is usable.
    """
    scale = model.time_scale
    free_at = {
        vid: (
            now_s + (remaining_s(active_by_vehicle[vid]) + model.overhead_s / 2) / scale
            if vid in active_by_vehicle
            else now_s
        )
        for vid in usable_vehicles
    }
    etas: dict[str, float] = {}
    if not free_at:
        return etas
    for job in queue:
        vid = min(free_at, key=lambda v: (free_at[v], v))
        start = free_at[vid]
        etas[job.job_id] = start - now_s + model.overhead_s / 2 / scale
        free_at[vid] = start + (job.estimate_s + model.overhead_s) / scale
    return etas

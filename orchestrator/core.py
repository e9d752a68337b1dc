"""The orchestrator's decisions (pure): jobs, queue, assignment, presence, operator commands.

A :class:`Book` is fed facts (a validated submission, an agent report, a vehicle status, a
liveliness change, an operator command, the passing of time) and returns :class:`Effects`: jobs
that changed (to store and publish), events, and commands for vehicles. It never touches the
network, the disk or a clock; the service (orchestrator/service.py, its outputs in
orchestrator/outputs.py) does, with what it returns.

Invariants (tests/test_orchestrator_core.py checks them with hypothesis): no job is lost or
duplicated; at most one active job per vehicle and per board; jobs are assigned in queue order
(priority, then submission order).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable, Mapping, Sequence

import msgspec

from bus.messages import (
    MAX_SNAPSHOT_ALERTS,
    AgentReport,
    CommandReply,
    Event,
    ShowSnapshot,
    SubmitReply,
    SubmitRequest,
    VehicleStatus,
)
from orchestrator import (
    assignment,
    battery_swaps,
    holders,
    job_intake,
    phrase_intake,
    phrases,
    positions,
    presence,
    reports,
)
from orchestrator.alerts import OpenAlerts
from orchestrator.batteries import Swaps
from orchestrator.battery_records import BatteryRecords
from orchestrator.core_types import CoreConfig, Effects, Level
from orchestrator.finished import MAX_FINAL_JOBS, FinishedJobs
from orchestrator.fleet import landing_of, queue_etas, usable_boards_of
from orchestrator.jobs import WAITING_STATES, Job
from orchestrator.kinds import KindMatch, KindPlans
from orchestrator.operator import apply_operator
from orchestrator.restart import (
    dirty_boards_at_start,
    drains_at_start,
    jobs_at_start,
    keys_of,
    sheets_at_start,
    vehicles_at_start,
)
from orchestrator.snapshot_jobs import snapshot_jobs
from orchestrator.vehicle_jobs import VehicleJobs

__all__ = ["MAX_FINAL_JOBS", "Book", "CoreConfig", "Effects", "Level"]


class Book:
    """All jobs and vehicles of a show, and the rules that move them."""

    def __init__(
        self,
        config: CoreConfig,
        jobs: Iterable[Job] = (),
        *,
        now_s: float,
        queue_paused: bool = False,
        paused_vehicles: Iterable[str] = (),
        held_vehicles: Iterable[str] = (),
        dirty_boards: Iterable[str] = (),
        sheet_boards: Iterable[str] = (),
        job_counts: Mapping[str, int] | None = None,
        max_final_jobs: int = MAX_FINAL_JOBS,
        open_alerts: Iterable[Event] = (),
        batteries: BatteryRecords | None = None,
    ) -> None:
        """``jobs``: the stored ones (every unfinished job and at least the latest finished);
        ``job_counts``: jobs per state in the database (default: counted from ``jobs``);
        ``open_alerts``: the alerts open when the orchestrator stopped; ``sheet_boards``: the
        boards that waited for the crew's sheet; ``batteries``: the swaps and drains stored."""
        self.config = config
        self.queue_paused = queue_paused
        self.vehicles = vehicles_at_start(config, now_s, paused=paused_vehicles, held=held_vehicles)
        self.jobs: dict[str, Job] = {}
        self._by_vehicle = VehicleJobs()
        """Vehicle id -> its active job, and the queued job that waits for it
        (``orchestrator/vehicle_jobs.py``)."""
        for job in jobs_at_start(jobs, now_s):
            self._index(None, job)
        self.finished = FinishedJobs(self.jobs.values(), job_counts, max_final_jobs)
        """Jobs per state and the held finished jobs (``orchestrator/finished.py``)."""
        self.next_seq = max((j.seq for j in self.jobs.values()), default=0) + 1
        self.by_key = keys_of(self.jobs.values())
        """(client_id, idempotency_key) -> job id of every keyed submission in memory."""
        self._forget(self.finished.overflow())
        self._announced: positions.Announced = {}
        self.alerts = OpenAlerts(open_alerts, self.vehicles)
        """Alerts whose cause lasts, for snapshots (``orchestrator/alerts.py``); kept with the
        settings, so a restart keeps them."""
        self.kinds = KindMatch({v.vehicle_id: v.kind for v in config.vehicles})
        """Which kind may take a job and how long it would write it (``orchestrator/kinds.py``)."""
        self.dirty_boards = dirty_boards_at_start(config, dirty_boards)
        """Boards left half-written: no job there until the operator's ``fresh_sheet``."""
        self.sheets = sheets_at_start(config, sheet_boards, now_s)
        """Boards waiting for the crew's sheet or drying (``orchestrator/sheets.py``)."""
        self.swaps = Swaps(time_scale=config.eta.time_scale, swap_s=config.battery_swap_s)
        """Vehicles waiting for the crew's battery swap (``orchestrator/batteries.py``)."""
        stored = batteries or BatteryRecords()
        self.drains = drains_at_start(stored, self.vehicles)
        """Each vehicle's drain learned from its reports (``orchestrator/battery_drain.py``)."""
        battery_swaps.restore(self, stored)
        self.router_down_since_s: float | None = None
        """Since when the orchestrator has had no link to the router, [s] (None: it has one)."""
        self.told_overdue: set[str] = set()
        """Jobs whose overdue wait for their holder was alerted (``holders.tell_overdue``)."""
        self.phrase_ready: dict[str, tuple[int, float]] = {}
        """Job id -> (attempt, time [s]) of the latest *ready* report of a phrase's character
        not acknowledged yet: its phrase starts when all are (``orchestrator/phrases.py``)."""

    # --- views ------------------------------------------------------------------------------
    @property
    def job_counts(self) -> Counter[str]:
        """Jobs per state, every stored job counted (not only those held)."""
        return self.finished.counts

    def queue(self) -> list[Job]:
        """Queued jobs in the order they will be assigned."""
        return sorted(
            (j for j in self.jobs.values() if j.state == "queued"), key=lambda j: j.sort_key
        )

    def waiting_count(self) -> int:
        return sum(1 for j in self.jobs.values() if j.state in ("awaiting_approval", "queued"))

    def active_job_of(self, vehicle_id: str) -> Job | None:
        job_id = self._by_vehicle.active.get(vehicle_id)
        return None if job_id is None else self.jobs[job_id]

    def awaited_by(self, vehicle_id: str) -> Job | None:
        """The queued job that was taken back from this lost vehicle and may wait for it."""
        job_id = self._by_vehicle.awaited.get(vehicle_id)
        return None if job_id is None else self.jobs[job_id]

    def vehicles_with_jobs(self) -> set[str]:
        """Ids of the vehicles holding an active job."""
        return set(self._by_vehicle.active)

    def active_jobs(self) -> list[Job]:
        """Assigned and writing jobs, in submission order."""
        return sorted((self.jobs[j] for j in self._by_vehicle.active.values()), key=lambda j: j.seq)

    def busy_boards(self) -> set[str]:
        return {j.board_id for j in self.active_jobs() if j.board_id is not None}

    def etas(self, now_s: float) -> dict[str, tuple[int, float | None]]:
        """Queue position (1 = next) and ETA in [s] of every queued job."""
        queue = self.queue()
        if not queue:
            return {}
        usable = usable_boards_of(self.vehicles)
        active = self.active_jobs()
        etas = (
            {}
            if self.queue_paused
            else queue_etas(
                queue,
                active,
                usable,
                now_s,
                self.config.eta,
                landing=landing_of(self.vehicles, usable, active),
                may_take=self.kinds.may_take,
                writing_s_on=self.kinds.writing_s_on,
                board_free_s={b: self.sheets.free_at_s(b, now_s) for b in usable.values()},
                after_character_s=self.sheets.after_character_s,
                charges=battery_swaps.eta_charges(self, now_s),
                row=phrases.board_row(self.config),
            )
        )
        return {j.job_id: (i + 1, etas.get(j.job_id)) for i, j in enumerate(queue)}

    def sheet_wanted(self) -> set[str]:
        """Boards waiting for a fresh sheet: half-written ones, those with a character the crew
        takes away (``orchestrator/sheets.py``), and those of lost vehicles whose job waits for
        them past its hold (``holders.tell_overdue``)."""
        return self.dirty_boards | self.sheets.waiting.keys() | holders.overdue_boards(self)

    def open_alerts(self) -> list[Event]:
        """The alerts whose cause lasts, oldest first (``orchestrator/alerts.py``)."""
        return self.alerts.current(self.vehicles, self.sheet_wanted())

    def snapshot(
        self,
        now_s: float,
        *,
        include_final: bool = True,
        max_final: int = MAX_FINAL_JOBS,
        strokes_budget_bytes: int = 0,
        events: Sequence[Event] = (),
    ) -> ShowSnapshot:
        """Everything a late joiner needs: jobs (in submission order), vehicles, open alerts.

        With ``include_final`` the latest ``max_final`` finished jobs are included too. Waiting
        drawn jobs carry their strokes, oldest first, while their JSON fits the budget.
        ``events``: the latest lines of the event log (the service reads them from its store).
        """
        jobs = snapshot_jobs(
            self.jobs.values(),
            self.etas(now_s),
            include_final=include_final,
            max_final=max_final,
            strokes_budget_bytes=strokes_budget_bytes,
        )
        vehicles = [
            view.summary(job.job_id if (job := self.active_job_of(vid)) else None)
            for vid, view in self.vehicles.items()
        ]
        return ShowSnapshot(
            show_id=self.config.show_id,
            time_s=now_s,
            queue_paused=self.queue_paused,
            jobs=jobs,
            vehicles=vehicles,
            events=list(events),
            alerts=self.open_alerts()[-MAX_SNAPSHOT_ALERTS:],
            dirty_boards=sorted(self.sheet_wanted()),
            job_counts={state: n for state, n in sorted(self.job_counts.items()) if n > 0},
        )

    # --- helpers ----------------------------------------------------------------------------
    def event(
        self,
        eff: Effects,
        now_s: float,
        level: Level,
        kind: str,
        message: str,
        *,
        vehicle_id: str | None = None,
        job_id: str | None = None,
    ) -> None:
        event = Event(
            time_s=now_s,
            level=level,
            kind=kind,
            message=message,
            vehicle_id=vehicle_id,
            job_id=job_id,
        )
        eff.events.append(event)
        if self.alerts.saw(event, self.vehicles):
            eff.settings_changed = True  # stored with the settings

    def settle(self, eff: Effects, now_s: float) -> Effects:
        """Add to ``eff.moved`` every other queued job whose position or ETA the decision changed
        (the protocol publishes a JobState on every change); returns ``eff``."""
        current = self.etas(now_s)
        eff.moved |= positions.announce(
            self._announced, current, eff.jobs.keys(), now_s, self.config.eta_tolerance_s
        )
        return eff

    def put(self, eff: Effects, job: Job) -> Job:
        previous = self.jobs.get(job.job_id)
        self._index(previous, job)
        if not _progress_only(previous, job):
            eff.progressed.discard(job.job_id)
        elif job.job_id not in eff.jobs:  # else: on top of a change of this decision, stored
            eff.progressed.add(job.job_id)
        eff.jobs[job.job_id] = job
        self.kinds.forget(job)
        self._forget(self.finished.changed(previous, job))
        if job.final and previous is not None and not previous.final:
            phrases.ended_unbegun(self, eff, job)  # a phrase is written whole or not at all
        return job

    def _forget(self, job_ids: Iterable[str]) -> None:
        """Drop finished jobs from memory (the database keeps them; the service answers a
        repeated idempotency key of a forgotten job from there)."""
        for job_id in job_ids:
            job = self.jobs.pop(job_id, None)
            if job is not None and job.idempotency_key is not None:
                self.by_key.pop((job.client_id, job.idempotency_key), None)

    def _index(self, previous: Job | None, job: Job) -> None:
        """Hold ``job`` (replacing ``previous``, its older version) and keep ``_by_vehicle``
        true."""
        self.jobs[job.job_id] = job
        self._by_vehicle.hold(previous, job)

    # --- submissions --------------------------------------------------------------------------
    def waiting_of(self, identity: str) -> int:
        """Jobs that ``identity`` submitted on the bus awaiting approval or queued."""
        jobs = self.jobs.values()
        return sum(1 for j in jobs if j.submitted_by == identity and j.state in WAITING_STATES)

    def submit(
        self,
        job_id: str,
        request: SubmitRequest,
        *,
        label: str,
        estimate_s: float,
        now_s: float,
        submitted_by: str | None = None,
    ) -> tuple[SubmitReply, Effects]:
        """Accept a validated submission (the caller parsed its glyph and checked its
        identity's quotas, ``orchestrator/quotas.py``); refuse when full.

        ``submitted_by``: the identity on the bus (None: not known, capped as any client).
        A repeated ``idempotency_key`` of the same client answers with the job it made first
        (and ``job_id`` is not used). The job is made by ``orchestrator/job_intake.py``."""
        return job_intake.submit(self, job_id, request, label, estimate_s, now_s, submitted_by)

    def submit_phrase(
        self,
        job_ids: Sequence[str],
        request: SubmitRequest,
        estimates_s: Sequence[float],
        *,
        now_s: float,
        submitted_by: str | None = None,
    ) -> tuple[SubmitReply, Effects]:
        """Accept a validated phrase: one job per character (``orchestrator/phrase_intake.py``)."""
        return phrase_intake.submit(self, job_ids, request, estimates_s, now_s, submitted_by)

    def submit_reply(self, job_id: str, now_s: float) -> SubmitReply:
        """The ``ok`` reply naming an accepted job, with its current state, place and ETA."""
        job = self.jobs[job_id]
        position, eta = self.etas(now_s).get(job_id, (None, None))
        return SubmitReply(
            ok=True, job_id=job_id, state=job.state, queue_position=position, eta_s=eta
        )

    def set_estimate(self, job_id: str, plans: KindPlans, now_s: float) -> Effects:
        """What each kind's planner made of a job: its duration in [s] by vehicle kind (the
        job's own estimate is the first vehicle's kind's, the shortest if that kind cannot plan
        it; the ETAs use the kind of the vehicle that would take it), and the kinds that cannot
        plan it, which are then not sent it while another kind may write it
        (``orchestrator/job_intake.py``)."""
        return job_intake.set_estimate(self, job_id, plans, now_s)

    # --- assignment (orchestrator/assignment.py) -----------------------------------------------
    def assign(self, eff: Effects, now_s: float) -> None:
        """Give queued jobs, in order, to ready vehicles whose board is free."""
        assignment.assign(self, eff, now_s)

    def assignment_result(
        self, vehicle_id: str, job_id: str, reply: CommandReply | None, now_s: float
    ) -> Effects:
        """The agent's answer to an assign command (None: no answer)."""
        return self.settle(assignment.answered(self, vehicle_id, job_id, reply, now_s), now_s)

    # --- vehicles and reports (orchestrator/presence.py, orchestrator/reports.py) ----------------
    def liveliness(self, vehicle_id: str, alive: bool, now_s: float) -> Effects:
        """A vehicle's token appeared or disappeared."""
        return self.settle(presence.liveliness(self, vehicle_id, alive, now_s), now_s)

    def router_link(self, up: bool, now_s: float) -> Effects:
        """The orchestrator's own link to the router went or came back."""
        return self.settle(presence.router_link(self, up, now_s), now_s)

    def status(self, status: VehicleStatus, now_s: float) -> Effects:
        """A vehicle's published status (a heartbeat that changes nothing moves no ETA)."""
        eff = presence.status(self, status, now_s)
        return self.settle(eff, now_s) if eff.fleet_changed or eff.jobs or eff.events else eff

    def telemetry(
        self,
        vehicle_id: str,
        tracking_error_m: float,
        job_id: str | None,
        now_s: float,
        *,
        writing: bool,
    ) -> Effects:
        """A telemetry sample: liveness, and an alert (at most every 5 s) on a large error while
        it writes. Not settled (the service applies these effects only when they hold events)."""
        return presence.telemetry(
            self, vehicle_id, tracking_error_m, job_id, now_s, writing=writing
        )

    def vehicle_event(self, vehicle_id: str, event: Event, now_s: float) -> Effects:
        """An event an agent published about its vehicle: into the show's log (rate-limited)."""
        return self.settle(presence.vehicle_event(self, vehicle_id, event, now_s), now_s)

    def tick(self, now_s: float) -> Effects:
        """Time passed: lost vehicles, unconfirmed jobs, then assignment."""
        eff = Effects()
        presence.tick_into(self, eff, now_s)
        return self.settle(eff, now_s)

    def report(self, rep: AgentReport, now_s: float) -> tuple[CommandReply, Effects]:
        """An agent's report; idempotent (agents retry until acknowledged)."""
        eff = Effects()
        reply = reports.apply_report(self, rep, eff, now_s)
        return reply, self.settle(eff, now_s)

    # --- operator -----------------------------------------------------------------------------
    def operator(self, command: object, now_s: float) -> tuple[CommandReply, Effects]:
        """An operator command (see orchestrator/operator.py)."""
        eff = Effects()
        reply = apply_operator(self, command, eff, now_s)
        self.assign(eff, now_s)
        return reply, self.settle(eff, now_s)

    def vehicle_ids(self, vehicle_id: str | None) -> Sequence[str]:
        """One vehicle (validated by the caller) or all."""
        return [vehicle_id] if vehicle_id is not None else list(self.vehicles)


def _progress_only(previous: Job | None, job: Job) -> bool:
    """Whether ``job`` differs from ``previous`` in its progress (and time of update) alone:
    published, not stored (``Effects.progressed``)."""
    if previous is None or previous.progress == job.progress:
        return False
    same = msgspec.structs.replace(previous, progress=job.progress, updated_at_s=job.updated_at_s)
    return same == job

"""The console's state: bus messages merged into a fleet, a queue, an event log and alerts.

Pure: no Textual and no Zenoh. :meth:`ConsoleModel.apply` takes any message from the bus (and the
console's own presence/command records) with the time it arrived; widgets read rows from it.
Telemetry of many vehicles is merged here, so widgets redraw at a bounded rate whatever the
message rate. Each area has a version counter so a view can tell whether it has to redraw.
The event log is :class:`tui.event_history.EventHistory` (``ConsoleModel.events``); the alerts
are raised by :func:`tui.records.current_alerts` (with the orchestrator's open alerts, so a
console that reconnects sees those it missed), the model keeps which ones were acknowledged.
"""

from __future__ import annotations

from typing import Literal

from bus.messages import (
    AIRBORNE_STATES,
    CommandReply,
    Event,
    JobState,
    OperatorCommand,
    ShowSnapshot,
    Telemetry,
    VehicleStatus,
    VehicleSummary,
)
from tui.event_history import EventHistory
from tui.inputs import BadPayload, BusInput, OrchestratorPresence, VehiclePresence
from tui.records import (
    AWAITING_JOB_STATES,
    FINAL_JOB_STATES,
    VehicleRecord,
    current_alerts,
    force_off,
    over_threshold,
    queue_rows,
    with_known_strokes,
)
from tui.rows import Alert, QueueRow, VehicleRow
from tui.settings import ConsoleSettings
from tui.tracks import Track, TrackPoint

GROUNDED_STATES = frozenset({"fault", "lost", "unknown"})
"""Vehicle states in which it cannot take a job whatever the operator does to the queue."""
OrchestratorStatus = Literal["unknown", "online", "offline"]


class ConsoleModel:
    """Fleet, queue, events and alerts as the console knows them."""

    def __init__(
        self, settings: ConsoleSettings, *, max_events: int = 500, max_finished: int = 100
    ):
        self.settings = settings
        self.max_finished = max_finished
        self._vehicles: dict[str, VehicleRecord] = {}
        self._order = {spec.vehicle_id: i for i, spec in enumerate(settings.vehicles)}
        for spec in settings.vehicles:
            self._vehicles[spec.vehicle_id] = VehicleRecord(
                spec.vehicle_id, spec.kind, spec.board_id, spec.surface
            )
        self._sorted_ids: list[str] | None = None
        self._jobs: dict[str, JobState] = {}
        self.events = EventHistory(max_events)
        """The event log: the show's events and the console's own notes."""
        self._acknowledged: set[str] = set()
        self.orchestrator: OrchestratorStatus = "unknown"
        """Whether the orchestrator's liveliness token exists (unknown before any news)."""
        self.orchestrator_changed_s: float | None = None
        """When :attr:`orchestrator` last changed (arrival time)."""
        self.last_snapshot_s: float | None = None
        """Arrival time of the latest snapshot or fleet message."""
        self.ended_unheard: set[str] = set()
        """Jobs unfinished here that the orchestrator listed, then a ``fleet`` publication (which
        lists no finished job) left out although they are older than it: they ended and their
        last message was lost; the console asks for the whole show again (cleared when it has).
        A job the orchestrator never listed (a rogue publisher's) is not its to end."""
        self._listed: set[str] = set()
        """The jobs the orchestrator's latest snapshot or ``fleet`` publication listed."""
        self.queue_paused = False
        self.job_counts: dict[str, int] = {}
        """Jobs of the show per state, all of them, as the orchestrator last counted (the job
        list keeps only the latest ``max_finished`` finished ones)."""
        self.dirty_boards: frozenset[str] = frozenset()
        """Boards left half-written: the orchestrator waits for the operator's fresh sheet."""
        self.open_alerts: tuple[Event, ...] = ()
        """The orchestrator's open alerts, as its latest snapshot or fleet said: those raised
        while the console was away too."""
        self.last_reply: tuple[OperatorCommand, CommandReply] | None = None
        self.fleet_version = 0
        self.queue_version = 0
        self.status_version = 0
        self.tracks_version = 0

    # --- reading ---------------------------------------------------------------------------------
    @property
    def version(self) -> int:
        """Changes whenever anything visible changes."""
        return (
            self.fleet_version
            + self.queue_version
            + self.status_version
            + self.tracks_version
            + self.events.seq
        )

    def vehicle_ids(self) -> list[str]:
        """Show-file vehicles first, in file order, then others by id."""
        if self._sorted_ids is None:
            big = len(self._order)
            self._sorted_ids = sorted(
                self._vehicles, key=lambda vid: (self._order.get(vid, big), vid)
            )
        return list(self._sorted_ids)

    def vehicle_row(self, vehicle_id: str, now_s: float) -> VehicleRow | None:
        v = self._vehicles.get(vehicle_id)
        if v is None:
            return None
        job = self._jobs.get(v.job_id) if v.job_id else None
        age = None if v.heard_s is None else max(0.0, now_s - v.heard_s)
        state = "lost" if v.alive is False else v.state
        if v.swap_note and state in ("idle", "landed"):
            state = "battery_swap"
        return VehicleRow(
            vehicle_id=v.vehicle_id,
            kind=v.kind,
            state=state,
            board_id=v.board_id,
            job_id=v.job_id,
            job_label=job.label if job else None,
            progress=job.progress if job and v.progress == 0.0 else v.progress,
            tracking_error_m=v.tracking_error_m,
            battery_fraction=v.battery_fraction,
            battery_minutes_left=v.battery_minutes_left,
            link_age_s=age,
            link_loss_fraction=v.link_loss_fraction,
            preflight=v.preflight,
            flight_s_today=v.flight_s_today,
            stale=age is not None and age > self.settings.lost_after_s,
            over_threshold=over_threshold(v, self.settings),
            message=v.swap_note or v.message,
            position_m_enu=v.position_m_enu,
            held=v.held,
            paused=v.paused,
            surface=v.surface,
            force_n=v.force_n,
            force_reference_n=v.force_reference_n,
            force_off=force_off(v, self.settings),
        )

    def vehicle_rows(self, now_s: float) -> list[VehicleRow]:
        rows = (self.vehicle_row(vid, now_s) for vid in self.vehicle_ids())
        return [row for row in rows if row is not None]

    def state_counts(self) -> dict[str, int]:
        """How many vehicles are in each state (``lost`` when their token vanished)."""
        counts: dict[str, int] = {}
        for v in self._vehicles.values():
            state = "lost" if v.alive is False else v.state
            counts[state] = counts.get(state, 0) + 1
        return counts

    def airborne_count(self) -> int:
        """Vehicles whose last known state is in the air (lost ones count: they may still fly)."""
        return sum(1 for v in self._vehicles.values() if v.state in AIRBORNE_STATES)

    def can_fly_count(self) -> int:
        """Vehicles that may take the next job: present, not held, not in fault."""
        return sum(
            1
            for v in self._vehicles.values()
            if v.alive is not False and not v.held and v.state not in GROUNDED_STATES
        )

    def fault_ids(self) -> list[str]:
        """Vehicles in ``fault`` (e.g. after an emergency stop), in display order."""
        vehicles = self._vehicles
        return [vid for vid in self.vehicle_ids() if vehicles[vid].state == "fault"]

    def held_ids(self) -> list[str]:
        """Vehicles held by the operator (land, estop), in display order."""
        vehicles = self._vehicles
        return [vid for vid in self.vehicle_ids() if vehicles[vid].held]

    def awaiting_count(self) -> int:
        return sum(1 for j in self._jobs.values() if j.state in AWAITING_JOB_STATES)

    def track(self, vehicle_id: str) -> Track | None:
        v = self._vehicles.get(vehicle_id)
        return None if v is None else v.track

    def vehicles_on_board(self, board_id: str) -> list[str]:
        vehicles = self._vehicles
        return [vid for vid in self.vehicle_ids() if vehicles[vid].board_id == board_id]

    def job(self, job_id: str | None) -> JobState | None:
        return self._jobs.get(job_id) if job_id else None

    def phrase_of(self, job: JobState | None) -> list[JobState]:
        """The known characters of ``job``'s phrase in reading order (none: not a phrase)."""
        if job is None or job.phrase is None:
            return []
        pid = job.phrase.phrase_id
        mine = [j for j in self._jobs.values() if j.phrase and j.phrase.phrase_id == pid]
        return sorted(mine, key=lambda j: j.phrase.index if j.phrase else 0)

    def queue_rows(self) -> list[QueueRow]:
        """Awaiting approval, queued (in queue order), active, then ended (newest first)."""
        return queue_rows(self._jobs.values())

    def alerts(self) -> list[Alert]:
        """Current alerts, minus the acknowledged ones (whose causes still last)."""
        current = self._all_alerts()
        self._acknowledged &= {a.key for a in current}
        return [a for a in current if a.key not in self._acknowledged]

    def acknowledge_alerts(self) -> int:
        """Hide the current alerts until their cause clears and comes back; returns how many."""
        current = self.alerts()
        self._acknowledged.update(a.key for a in current)
        self.status_version += 1
        return len(current)

    def _all_alerts(self) -> list[Alert]:
        vehicles = [self._vehicles[vid] for vid in self.vehicle_ids()]
        offline = self.orchestrator == "offline"
        jobs = self._jobs.values()
        return current_alerts(
            offline, vehicles, jobs, self.dirty_boards, self.settings, self.open_alerts
        )

    # --- writing ---------------------------------------------------------------------------------
    def apply(self, item: BusInput, now_s: float) -> None:
        """Merge one message that arrived at ``now_s`` (console clock, in [s])."""
        if isinstance(item, Telemetry):
            self._telemetry(item, now_s)
        elif isinstance(item, VehicleStatus):
            self._status(item, now_s)
        elif isinstance(item, JobState):
            self._job(item)
        elif isinstance(item, Event):
            self.events.show_event(item)
        elif isinstance(item, ShowSnapshot):
            self.apply_snapshot(item, now_s, full=False)
        elif isinstance(item, VehiclePresence):
            self._presence(item)
        elif isinstance(item, OrchestratorPresence):
            self._orchestrator(item.alive, now_s)
        elif isinstance(item, BadPayload):
            self.events.note(
                now_s, "warning", "bad_message", f"unreadable message on {item.key}: {item.message}"
            )

    def apply_snapshot(self, snapshot: ShowSnapshot, now_s: float, *, full: bool) -> None:
        """A ``snapshot`` answer (``full``: it lists every job) or a ``fleet`` publication."""
        if snapshot.show_id != self.settings.show_id:
            self.events.note(
                now_s, "warning", "bad_message", f"snapshot of show {snapshot.show_id!r} ignored"
            )
            return
        if full:
            # Live updates that arrived while the query was under way are newer: keep them.
            jobs = {j.job_id: j for j in self._jobs.values() if j.updated_at_s > snapshot.time_s}
            for job in snapshot.jobs:
                known = jobs.get(job.job_id)
                if known is None or known.updated_at_s <= job.updated_at_s:
                    jobs[job.job_id] = with_known_strokes(job, self._jobs.get(job.job_id))
            self._jobs = jobs
            self.ended_unheard = set()
            self._listed = {job.job_id for job in snapshot.jobs}
            self._evict_finished()
            self.queue_version += 1
            self.events.history(snapshot.events)
        else:
            for job in snapshot.jobs:
                self._job(job)
            listed = {job.job_id for job in snapshot.jobs}
            self.ended_unheard = {
                j.job_id
                for j in self._jobs.values()
                if j.state not in FINAL_JOB_STATES
                and j.job_id in self._listed
                and j.job_id not in listed
                and j.updated_at_s < snapshot.time_s
            }
            self._listed = listed
        for summary in snapshot.vehicles:
            self._summary(summary, now_s)
        if self.dirty_boards != frozenset(snapshot.dirty_boards):
            self.dirty_boards = frozenset(snapshot.dirty_boards)
            self.status_version += 1
            self.tracks_version += 1  # board titles say it
        if self.open_alerts != tuple(snapshot.alerts):
            self.open_alerts = tuple(snapshot.alerts)
            self.status_version += 1
        if self.queue_paused != snapshot.queue_paused:
            self.queue_paused = snapshot.queue_paused
            self.status_version += 1
        if self.job_counts != snapshot.job_counts:
            self.job_counts = dict(snapshot.job_counts)
            self.status_version += 1
        self.last_snapshot_s = now_s
        self.fleet_version += 1

    def record_command(self, command: OperatorCommand, reply: CommandReply, now_s: float) -> None:
        """An operator command and the orchestrator's answer (kept for the status line).

        A refused or unanswered command is also logged here; accepted ones are logged by the
        orchestrator itself, so they are not repeated.
        """
        self.last_reply = (command, reply)
        self.status_version += 1
        if not reply.ok:
            self.events.command_refused(command, reply, now_s)

    def _vehicle(self, vehicle_id: str) -> VehicleRecord:
        v = self._vehicles.get(vehicle_id)
        if v is None:
            v = self._vehicles[vehicle_id] = VehicleRecord(vehicle_id)
            self._sorted_ids = None
        return v

    def _telemetry(self, t: Telemetry, now_s: float) -> None:
        v = self._vehicle(t.vehicle_id)
        v.state = t.state
        v.position_m_enu = t.position_m_enu
        v.tracking_error_m = t.tracking_error_m
        if t.battery_fraction is not None:
            v.battery_fraction = t.battery_fraction
        v.job_id = t.job_id
        v.progress = t.progress
        v.force_n = t.force_n
        v.force_reference_n = t.force_reference_n
        v.heard_s = now_s
        if v.alive is None:
            v.alive = True
        v.track.add(
            t.job_id,
            TrackPoint(
                t.position_m_enu, t.reference_m_enu, t.pen_down, t.force_n, t.force_reference_n
            ),
        )
        self.fleet_version += 1
        self.tracks_version += 1

    def _status(self, s: VehicleStatus, now_s: float) -> None:
        v = self._vehicle(s.vehicle_id)
        v.kind = s.kind or v.kind
        v.state = s.state
        v.board_id = s.board_id or v.board_id
        if s.job_id != v.job_id:
            v.progress = 0.0
        v.job_id = s.job_id
        v.message = s.message
        if s.battery_fraction is not None:
            v.battery_fraction = s.battery_fraction
            v.battery_minutes_left = s.battery_minutes_left
        v.preflight, v.link_loss_fraction = s.preflight, s.link_loss_fraction
        v.flight_s_today = s.flight_s_today if s.flight_s_today is not None else v.flight_s_today
        v.heard_s = now_s
        if v.alive is None:
            v.alive = True
        self.fleet_version += 1

    def _summary(self, s: VehicleSummary, now_s: float) -> None:
        """The orchestrator's view; the vehicle's own recent messages take precedence."""
        v = self._vehicle(s.vehicle_id)
        v.kind = v.kind or s.kind
        v.board_id = v.board_id or s.board_id
        v.held = s.held
        v.paused = s.paused
        v.swap_note = s.message if s.state == "battery_swap" else ""
        if v.battery_fraction is None:
            v.battery_fraction = s.battery_fraction
            v.battery_minutes_left = s.battery_minutes_left
        if v.alive is None:
            v.alive = s.alive
        recent = v.heard_s is not None and now_s - v.heard_s <= self.settings.lost_after_s
        if v.flight_s_today is None:
            v.flight_s_today = s.flight_s_today
        if s.state == "lost" or not recent:
            v.preflight = s.preflight
            v.state = s.state
            v.job_id = s.job_id
            v.message = s.message or v.message

    def _job(self, job: JobState) -> None:
        known = self._jobs.get(job.job_id)
        if known is not None and known.updated_at_s > job.updated_at_s:
            return
        self._jobs[job.job_id] = with_known_strokes(job, known)
        self._evict_finished()
        self.queue_version += 1
        self.fleet_version += 1

    def _evict_finished(self) -> None:
        finished = [j for j in self._jobs.values() if j.state in FINAL_JOB_STATES]
        if len(finished) <= self.max_finished:
            return
        finished.sort(key=lambda j: j.updated_at_s)
        for job in finished[: len(finished) - self.max_finished]:
            del self._jobs[job.job_id]

    def _presence(self, p: VehiclePresence) -> None:
        v = self._vehicle(p.vehicle_id)
        if v.alive != p.alive:
            v.alive = p.alive
            if p.alive and v.state == "lost":
                v.state = "unknown"
            self.fleet_version += 1

    def _orchestrator(self, alive: bool, now_s: float) -> None:
        status: OrchestratorStatus = "online" if alive else "offline"
        if status == self.orchestrator:
            return
        previous = self.orchestrator
        self.orchestrator = status
        self.orchestrator_changed_s = now_s
        self.status_version += 1
        if not alive:
            self.events.note(
                now_s, "alert", "orchestrator", "orchestrator gone; last known state kept"
            )
        elif previous == "offline":
            self.events.note(now_s, "info", "orchestrator", "orchestrator back")

"""The orchestrator's outputs: a :class:`~orchestrator.core.Book` and where its decisions go.

:meth:`BookOutputs.apply` carries out the :class:`~orchestrator.core.Effects` of a decision in the
order that keeps acknowledged data safe: store (one SQLite transaction), then publish, then send
to vehicles; a database failure stops the service (crash-only). The history kept in the database
is compacted here too. The inputs that feed the Book (queries, subscriptions, timers) are
:class:`~orchestrator.service.OrchestratorService`'s.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Callable, Coroutine
from typing import Any

import msgspec

from bus.bridge import LatestByKey
from bus.keys import ShowKeys
from bus.messages import CommandReply, VehicleCommand, VehicleStatus
from bus.pubsub import publish
from bus.recorder import McapRecorder
from bus.rpc import NoReplyError, RemoteError, aquery_one
from bus.session import Session
from orchestrator import battery_swaps
from orchestrator.compaction import CompactionSchedule, HistoryPolicy
from orchestrator.core import MAX_FINAL_JOBS, Book, CoreConfig, Effects
from orchestrator.estimates import DurationEstimates
from orchestrator.fleet import EtaModel, VehicleInfo
from orchestrator.jobs import to_state
from orchestrator.sheets import BoardSheets
from orchestrator.store import JobStore, StoreError
from orchestrator.written import with_written
from showfile import Show
from showfile.checks import cannot_write
from vehicles.batteries import kind_battery

log = logging.getLogger(__name__)

VEHICLE_COMMAND_TIMEOUT_S = 2.0
"""How long an agent has to answer a command, [s]."""


def core_config(show: Show) -> CoreConfig:
    """The Book's policy from a show file."""
    return CoreConfig(
        show_id=show.show_id,
        vehicles=tuple(
            VehicleInfo(v.id, v.kind, v.board, cannot_write=cannot_write(show, v))
            for v in show.vehicles
        ),
        moderation=show.policy.moderation,
        lost_after_s=show.policy.lost_after_s,
        lost_job_hold_s=show.policy.lost_job_hold_s,
        max_queue=show.policy.max_queue,
        max_awaiting=show.policy.max_awaiting,
        max_attempts=show.policy.max_attempts,
        max_handbacks=show.policy.max_handbacks,
        tracking_error_alert_m=show.policy.tracking_error_alert_m,
        eta=EtaModel(time_scale=show.time_scale),
        boards=tuple((b.id, BoardSheets(b.sheets, b.dry_s)) for b in show.boards),
        sheet_change_s=show.policy.sheet_change_s,
        batteries=tuple((k, kind_battery(k)) for k in sorted({v.kind for v in show.vehicles})),
        battery_reserve_fraction=show.battery.reserve_fraction,
        battery_swap_s=show.battery.swap_s,
        clock_offset_max_s=show.preflight.clock_offset_max_s,
    )


def history_policy(show: Show) -> HistoryPolicy:
    """How much history the show's database keeps."""
    age_h = show.storage.job_history_max_age_h
    return HistoryPolicy(
        budget_bytes=int(show.storage.database_budget_mb * 1e6),
        max_age_s=None if age_h is None else age_h * 3600.0,
    )


class BookOutputs:
    """One show's Book on an open session and store: its effects stored, published and sent."""

    def __init__(
        self,
        show: Show,
        session: Session,
        store: JobStore,
        *,
        recorder: McapRecorder | None = None,
        clock: Callable[[], float] = time.time,
    ) -> None:
        self.show, self.session, self.store, self.recorder = show, session, store, recorder
        self.keys = ShowKeys(show.show_id)
        self.clock = clock
        stored = store.load(max_final=MAX_FINAL_JOBS)
        self.book = Book(
            core_config(show),
            stored.jobs,
            now_s=clock(),
            job_counts=stored.job_counts,
            queue_paused=stored.queue_paused,
            paused_vehicles=stored.paused_vehicles,
            held_vehicles=stored.held_vehicles,
            dirty_boards=stored.dirty_boards,
            sheet_boards=stored.sheet_boards,
            open_alerts=stored.open_alerts,
            batteries=stored.batteries,
        )
        self.estimates = DurationEstimates(show)
        """Planned durations for queue ETAs (``orchestrator/estimates.py``)."""
        self._tasks: set[asyncio.Task[Any]] = set()
        self._stop: asyncio.Event | None = None
        self.fatal: BaseException | None = None
        """Set when the database failed; the service's
        :meth:`~orchestrator.service.OrchestratorService.run` raises it after stopping."""
        self.history = history_policy(show)
        self._compaction = CompactionSchedule()
        self.fleet_changed = False
        """The fleet snapshot changed since it was last published (every ``TICK_PERIOD_S`` at
        most: 250 vehicles coming or going were as many 50 kB snapshots, each encoded, sent
        and recorded)."""
        self._disk_alerted = False
        """The disk-full alert was raised for the reserve given up last."""
        self.statuses: LatestByKey[str, VehicleStatus] | None = None
        """The newest undecided status of each vehicle (made in the loop by
        :meth:`~orchestrator.service.OrchestratorService.run`)."""
        log.info("show %s: %d jobs restored", show.show_id, len(stored.jobs))

    # --- effects ------------------------------------------------------------------------------
    def apply(self, eff: Effects) -> None:
        """Store, then publish, then send: the order that keeps acknowledged data safe."""
        if eff.empty:
            return
        settings: dict[str, Any] = {}
        if eff.settings_changed:
            settings = {
                "queue_paused": self.book.queue_paused,
                "paused_vehicles": [v for v, view in self.book.vehicles.items() if view.paused],
                "held_vehicles": [v for v, view in self.book.vehicles.items() if view.held],
                "dirty_boards": self.book.dirty_boards,
                "sheet_boards": list(self.book.sheets.waiting),
                "open_alerts": self.book.open_alerts(),
                "batteries": battery_swaps.records(self.book),
            }
        try:
            changed = [job for job_id, job in eff.jobs.items() if job_id not in eff.progressed]
            self.store.save(changed, eff.events, written=eff.written, **settings)
        except Exception as exc:
            # Memory and disk may now disagree: stop, and let the supervisor restart us from
            # the database (crash-only). The caller's query gets an ``internal`` error.
            log.critical("cannot store state, stopping: %s", exc)
            self.fatal = exc
            if self._stop is not None:
                self._stop.set()
            raise
        self._compaction.finished += sum(1 for job in eff.jobs.values() if job.final)
        now = self.clock()
        etas = self.book.etas(now) if eff.jobs or eff.moved else {}
        moved = [
            self.book.jobs[j] for j in sorted(eff.moved - eff.jobs.keys()) if j in self.book.jobs
        ]
        for job in [*eff.jobs.values(), *moved]:  # moved: only their position/ETA changed
            position, eta = etas.get(job.job_id, (None, None))
            with_strokes = job.job_id in eff.jobs
            state = to_state(job, queue_position=position, eta_s=eta, with_strokes=with_strokes)
            state = with_written(state, eff.written.get(job.job_id))
            self._publish(self.keys.job(job.job_id), state)
        for event in eff.events:
            self._publish(self.keys.events, event)
        if eff.fleet_changed or eff.jobs or eff.moved:
            self.fleet_changed = True  # published by the timer: many changes, one snapshot
        for vehicle_id, command in eff.commands:
            self._spawn(self._send(vehicle_id, command))

    def _publish_fleet(self) -> None:
        self.fleet_changed = False
        self._publish(self.keys.fleet, self.book.snapshot(self.clock(), include_final=False))

    def _publish(self, key: str, message: msgspec.Struct) -> None:
        try:
            publish(self.session, key, message)
        except Exception as exc:  # the session is closing
            log.warning("cannot publish on %s: %s", key, exc)

    def _spawn(self, coro: Coroutine[Any, Any, None]) -> None:
        task = asyncio.get_running_loop().create_task(coro)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    async def _send(self, vehicle_id: str, command: VehicleCommand) -> None:
        if command.command == "assign":
            key = self.keys.vehicle_assign(vehicle_id)
        else:
            key = self.keys.vehicle_command(vehicle_id)
        self._record(key + "#request", command)
        reply: CommandReply | None
        try:
            reply = await aquery_one(
                self.session, key, command, CommandReply, timeout_s=VEHICLE_COMMAND_TIMEOUT_S
            )
        except RemoteError as exc:
            reply = CommandReply(ok=False, message=exc.info.message, error=exc.info)
        except NoReplyError:
            reply = None
        if reply is not None:
            self._record(key + "#reply", reply)
        log.info("%s %s -> %s", vehicle_id, command.command, reply.message if reply else "no reply")
        if command.command == "assign" and command.job is not None:
            now = self.clock()
            self.apply(self.book.assignment_result(vehicle_id, command.job.job_id, reply, now))

    def _record(self, topic: str, message: msgspec.Struct) -> None:
        if self.recorder is not None:
            self.recorder.record_message(topic, message)

    def watch_disk(self, now_s: float) -> None:
        """Say when a write gave the disk reserve up (``orchestrator/disk_room.py``), and make
        the reserve again once the disk has room."""
        reserve = self.store.reserve
        if reserve is None or not self.store.reserve_given_up:
            return
        eff = Effects()
        if not self._disk_alerted:
            self._disk_alerted = True
            reserve_mb = reserve.size_bytes / 1e6
            message = (
                f"the show's disk is full: the orchestrator writes on its {reserve_mb:.0f} MB"
                " reserve; no new character is taken until room is made"
            )
            self.book.event(eff, now_s, "alert", "disk_full", message)
        elif reserve.make(self.show.storage.min_free_mb * 1e6):
            self.store.reserve_given_up = self._disk_alerted = False
            message = "the show's disk has room again: new characters are taken"
            self.book.event(eff, now_s, "info", "disk_room", message)
        self.apply(eff)

    def compact_history(self, now_s: float) -> None:
        """Keep the database within the show's history policy when due (small transactions;
        a failure is logged and retried: memory and disk still agree)."""
        if not self._compaction.due(now_s):
            return
        try:
            result = self.store.compact(self.history, now_s, resume=self._compaction.more)
        except StoreError as exc:
            log.error("cannot compact the database (retried later): %s", exc)
            self._compaction.ran(now_s, more=False)
            return
        self._compaction.ran(now_s, more=result.more)
        if result.jobs or result.folded or result.events:
            log.info(
                "database compacted: %d jobs, %d folded, %d events; %.1f -> %.1f MB",
                result.jobs,
                result.folded,
                result.events,
                result.before_bytes / 1e6,
                result.after_bytes / 1e6,
            )
        if not result.more and result.after_bytes > self.history.budget_bytes:
            log.warning(
                "database %.1f MB over its %.1f MB budget: unfinished jobs, the newest finished"
                " and every idempotency key are kept",
                result.after_bytes / 1e6,
                self.history.budget_bytes / 1e6,
            )

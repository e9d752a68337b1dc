"""The orchestrator process: the pure :class:`~orchestrator.core.Book` wired to Zenoh and SQLite.

Every input (query, status, liveliness change, timer) is handled in the asyncio loop, one at a
time: decide (Book) -> store (one SQLite transaction) -> publish / reply / send. A submission is
therefore committed before its acknowledgement leaves. Zenoh callbacks only push into bridge
channels or schedule coroutines.

Vehicle statuses are the bulk of the traffic (every agent's heartbeat: 250 vehicles send several
hundred a second). They are state, not events: only the newest of each vehicle matters, so they
are merged per vehicle (``STATUS_MERGE_S``) and decided in chunks between which the loop serves
queries: a report or submission never waits behind a flood of statuses.
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import logging
import os
import time
import uuid
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import msgspec

from bus.bridge import FifoChannel, LatestByKey, RingChannel
from bus.keys import ShowKeys, identity_under, vehicle_id_from_key
from bus.messages import (
    AgentReport,
    CommandReply,
    ErrorInfo,
    Event,
    OperatorCommand,
    ShowSnapshot,
    SubmitReply,
    SubmitRequest,
    Telemetry,
    VehicleStatus,
)
from bus.pubsub import (
    Subscriber,
    declare_token,
    subscribe,
    subscribe_raw,
    watch_liveliness,
    watch_router_link,
)
from bus.rpc import serve, serve_async, serve_async_keyed
from bus.session import Session
from orchestrator.clock_offsets import clock_reply
from orchestrator.disk_room import storage_full
from orchestrator.operator import refused, signed_by
from orchestrator.outputs import BookOutputs
from orchestrator.quotas import OPERATOR, SubmitQuotas, quota_policy
from orchestrator.submissions import Accepted, SubmissionError, validate_submission
from orchestrator.written import attach_written
from showfile import Show

log = logging.getLogger(__name__)

TICK_PERIOD_S = 0.1
"""Wall time between timer decisions (loss detection, confirmation, assignment), [s]."""
SNAPSHOT_STROKES_BYTES = 300_000
"""JSON bytes of waiting jobs' strokes a ``snapshot`` reply carries at most (replies stay well
under ``bus.codec.MAX_PAYLOAD_BYTES``); ``jobs/<id>`` publications always carry them."""
STATUS_MERGE_S = 0.05
"""Wall time over which vehicles' statuses are merged, the newest per vehicle kept, [s]: at most
20 rounds of decisions a second however many vehicles speak (telemetry is merged likewise)."""
STATUS_CHUNK = 32
"""Statuses decided between two turns of the event loop: a query waits for one chunk at most
(about 1 ms), not for every status that arrived before it."""
SNAPSHOT_EVENTS = 50
"""Latest lines of the event log a ``snapshot`` reply carries: a few hundred bytes each, at most
about 115 kB (an operator's name and reason of 1000 characters each); the open alerts as much."""
SNAPSHOT_WRITTEN_BYTES = 100_000
"""JSON bytes of done jobs' ink pictures a ``snapshot`` reply carries at most, newest first
(about 25 jobs); strokes and pictures together stay under half the payload limit."""
ROUTER_LINK = ""
"""The key under which the router link's changes join the vehicle tokens' (no token has it)."""


def new_job_id() -> str:
    """A short unique job id (also a Zenoh key chunk)."""
    return "j" + uuid.uuid4().hex[:12]


def recording_path(show: Show, now_s: float) -> Path:
    """One MCAP file per run: ``<recordings_dir>/<show_id>-<UTC time>-<pid>.mcap``."""
    stamp = time.strftime("%Y%m%dT%H%M%SZ", time.gmtime(now_s))
    return show.recordings_dir / f"{show.show_id}-{stamp}-{os.getpid()}.mcap"


def _own_key(key: str, vehicle_id: str) -> bool:
    """Whether a vehicle's message came on that vehicle's own key (access control lets each
    agent publish only under its own keys, so the key, not the payload, says who sent it)."""
    try:
        return vehicle_id_from_key(key) == vehicle_id
    except ValueError:
        return False


def subscribe_telemetry(
    session: Session, keys: ShowKeys, latest: LatestByKey[str, Telemetry]
) -> Subscriber[None]:
    """The orchestrator's telemetry intake: every vehicle's telemetry, kept in ``latest`` (the
    newest of each vehicle) when it came on that vehicle's own key. ``benchmarks/bench_bus.py``
    measures this path against raw Zenoh."""
    return subscribe(
        session,
        keys.telemetry_all,
        Telemetry,
        lambda k, m: latest.push(m.vehicle_id, m) if _own_key(k, m.vehicle_id) else None,
    )


class OrchestratorService(BookOutputs):
    """One show's orchestrator on an open session; :meth:`run` until ``stop`` is set."""

    # --- queryables ---------------------------------------------------------------------------
    @functools.cached_property
    def quotas(self) -> SubmitQuotas:
        """Each identity's submission quotas (``orchestrator/quotas.py``)."""
        return SubmitQuotas(quota_policy(self.show))

    async def on_submit_as(self, asked_key: str, request: SubmitRequest) -> SubmitReply:
        """A submission on ``submit/<identity>``: the key says who (access control lets each
        certificate query only its own)."""
        identity = identity_under(self.keys.submit, asked_key)
        if identity is None:
            message = f"submit on {self.keys.submit}/<your certificate's name>, not {asked_key}"
            return SubmitReply(ok=False, error=ErrorInfo(code="forbidden", message=message))
        return await self.on_submit(request, identity)

    async def on_submit(self, request: SubmitRequest, identity: str = OPERATOR) -> SubmitReply:
        """A submission from ``identity`` (the operator's on the plain ``submit`` key): a repeat
        gets its job; then the identity's quotas; then validation and the Book."""
        key = self.keys.submit if identity == OPERATOR else self.keys.submit_as(identity)
        self._record(key + "#request", request)
        reply = self._repeated_submission(request)
        if reply is None:
            count = len(request.text or "") if request.phrase else 1  # a phrase: its characters
            waiting = self.book.waiting_of(identity)
            refusal = self.quotas.refusal(identity, waiting, self.clock(), count=count)
            if refusal is None:
                reply = self._take_submission(request, identity)
            else:  # debug: a flood must not flood the log too
                log.debug("submission of %s refused: %s", identity, refusal.message)
                reply = SubmitReply(ok=False, error=refusal)
        self._record(key + "#reply", reply)
        return reply

    def _take_submission(self, request: SubmitRequest, identity: str) -> SubmitReply:
        full = storage_full(self.show.database_path, self.show.storage.min_free_mb * 1e6)
        if full is not None:
            log.warning("submission refused: %s", full.message)
            return SubmitReply(ok=False, error=full)
        try:
            accepted = validate_submission(request, self.show)
        except SubmissionError as exc:
            return SubmitReply(ok=False, error=exc.info)
        if accepted.characters:
            return self._take_phrase(request, accepted, identity)
        job_id = new_job_id()
        reply, eff = self.book.submit(
            job_id,
            request,
            label=accepted.label,
            estimate_s=accepted.estimate_s,
            now_s=self.clock(),
            submitted_by=identity,
        )
        self.apply(eff)  # committed to SQLite before the reply is sent
        if reply.ok:
            key = f"text:{request.text}" if request.text is not None else None
            self._spawn(self._refine_estimate(job_id, accepted.glyph, key))
        return reply

    def _take_phrase(
        self, request: SubmitRequest, accepted: Accepted, identity: str
    ) -> SubmitReply:
        """A phrase: one job per character (``orchestrator/phrases.py``), stored first."""
        job_ids = [new_job_id() for _ in accepted.characters]
        estimates_s = [c.estimate_s for c in accepted.characters]
        reply, eff = self.book.submit_phrase(
            job_ids, request, estimates_s, now_s=self.clock(), submitted_by=identity
        )
        self.apply(eff)
        if reply.ok and reply.job_id == job_ids[0]:
            for job_id, char in zip(job_ids, accepted.characters, strict=True):
                self._spawn(self._refine_estimate(job_id, char.glyph, f"text:{char.label}"))
        return reply

    def _repeated_submission(self, request: SubmitRequest) -> SubmitReply | None:
        """The reply to a repeated idempotency key (its job, held by the Book or, finished long
        ago, in the database), or None: a retry is answered before any quota counts it."""
        key = request.idempotency_key
        if key is None:
            return None
        first = self.book.by_key.get((request.client_id, key))
        if first is not None and first in self.book.jobs:
            return self.book.submit_reply(first, self.clock())
        job = self.store.job_by_key(request.client_id, key)
        return None if job is None else SubmitReply(ok=True, job_id=job.job_id, state=job.state)

    async def _refine_estimate(self, job_id: str, glyph: Any, cache_key: str | None) -> None:
        """Replace the rough estimate by the planner's duration (best effort, bounded work)."""
        plans = await self.estimates.planned(job_id, glyph, cache_key)
        if plans.known:
            self.apply(self.book.set_estimate(job_id, plans, self.clock()))

    async def on_command_as(self, asked_key: str, command: OperatorCommand) -> CommandReply:
        """A command on ``command/<identity>``: the key says who (access control lets each
        outside operator query only its own)."""
        identity = identity_under(self.keys.command, asked_key)
        if identity is None:
            message = f"command on {self.keys.command}/<your certificate's name>, not {asked_key}"
            info = ErrorInfo(code="forbidden", message=message)
            return CommandReply(ok=False, message=message, error=info)
        return await self.on_command(command, identity)

    async def on_command(self, command: OperatorCommand, identity: str = OPERATOR) -> CommandReply:
        """A command from ``identity`` (the console's and the CLI's on the plain ``command``
        key). The event log names the identity, with the name the sender declared beside it
        when that differs (:func:`orchestrator.operator.signed_by`)."""
        key = self.keys.command if identity == OPERATOR else self.keys.command_as(identity)
        self._record(key + "#request", command)
        who = signed_by(identity, command.operator)
        command = msgspec.structs.replace(command, operator=who)
        reply = refused(identity, command)
        if reply is None:
            reply, eff = self.book.operator(command, self.clock())
            self.apply(eff)
        log.info("%s %s -> %s", command.operator, command.command, reply.message)
        self._record(key + "#reply", reply)
        return reply

    async def on_report(self, vehicle_id: str, report: AgentReport) -> CommandReply:
        """A report on ``vehicle_id``'s own key (only that agent may query it)."""
        key = self.keys.report(vehicle_id)
        self._record(key + "#request", report)
        if report.vehicle_id != vehicle_id:
            info = ErrorInfo(
                code="forbidden",
                message=f"a report on {vehicle_id}'s key names {report.vehicle_id!r}",
                field="vehicle_id",
            )
            reply = CommandReply(ok=False, message=info.message, error=info)
        else:
            reply, eff = self.book.report(report, self.clock())
            self.apply(eff)
        self._record(key + "#reply", reply)
        return reply

    async def on_snapshot(self, _: None) -> ShowSnapshot:
        """The whole show; its latest events come from the database (a restart keeps them)."""
        snapshot = self.book.snapshot(
            self.clock(),
            strokes_budget_bytes=SNAPSHOT_STROKES_BYTES,
            events=self.store.events(SNAPSHOT_EVENTS),
        )
        return attach_written(snapshot, self.store.written, SNAPSHOT_WRITTEN_BYTES)

    # --- subscriptions ------------------------------------------------------------------------
    async def _follow_presence(self, changes: FifoChannel[tuple[str, bool]]) -> None:
        """Vehicle tokens and the router link, in the order Zenoh told them (a restarted
        router's link opens before the tokens come back over it)."""
        async for key, alive in changes:
            if key == ROUTER_LINK:
                self.apply(self.book.router_link(alive, self.clock()))
                continue
            with contextlib.suppress(ValueError):
                self.apply(self.book.liveliness(vehicle_id_from_key(key), alive, self.clock()))

    def open_status_intake(self) -> LatestByKey[str, VehicleStatus]:
        """Where :meth:`receive_status` keeps statuses until decided (call in the loop)."""
        self.statuses = LatestByKey()
        return self.statuses

    def receive_status(self, key: str, status: VehicleStatus) -> None:
        """A decoded status from the bus (Zenoh's thread): kept, the newest of its vehicle, if it
        came on that vehicle's own key."""
        if self.statuses is not None and _own_key(key, status.vehicle_id):
            self.statuses.push(status.vehicle_id, status)

    async def decide_statuses(self, statuses: Iterable[VehicleStatus]) -> None:
        """Decide statuses one by one, letting the loop serve queries every ``STATUS_CHUNK``."""
        for count, status in enumerate(statuses, start=1):
            self.apply(self.book.status(status, self.clock()))
            if count % STATUS_CHUNK == 0:
                await asyncio.sleep(0)

    async def _follow_status(self, statuses: LatestByKey[str, VehicleStatus]) -> None:
        while True:
            await self.decide_statuses((await statuses.take()).values())
            await asyncio.sleep(STATUS_MERGE_S)

    async def _follow_vehicle_events(self, events: RingChannel[tuple[str, Event]]) -> None:
        async for key, event in events:
            with contextlib.suppress(ValueError):
                vehicle_id = vehicle_id_from_key(key)
                self.apply(self.book.vehicle_event(vehicle_id, event, self.clock()))

    async def _follow_telemetry(self, latest: LatestByKey[str, Telemetry]) -> None:
        while True:
            for sample in (await latest.take()).values():
                eff = self.book.telemetry(
                    sample.vehicle_id,
                    sample.tracking_error_m,
                    sample.job_id,
                    self.clock(),
                    writing=sample.state == "writing",
                )
                if eff.events:
                    self.apply(eff)
            await asyncio.sleep(0.05)  # merge telemetry: at most 20 decisions per second

    async def _timers(self) -> None:
        next_fleet = 0.0
        while True:
            await asyncio.sleep(TICK_PERIOD_S)
            now = self.clock()
            self.apply(self.book.tick(now))
            self.compact_history(now)
            self.watch_disk(now)
            if self.fleet_changed or now >= next_fleet:
                self._publish_fleet()
            if now >= next_fleet:
                next_fleet = now + self.show.policy.fleet_period_s
                if self.recorder is not None:
                    self.recorder.flush()

    # --- run ----------------------------------------------------------------------------------
    def _declare(self) -> list[Any]:
        keys, s = self.keys, self.session
        presence: FifoChannel[tuple[str, bool]] = FifoChannel()
        statuses = self.open_status_intake()
        telemetry: LatestByKey[str, Telemetry] = LatestByKey()
        vehicle_events: RingChannel[tuple[str, Event]] = RingChannel(256)
        declared: list[Any] = []
        if self.recorder is not None:
            rec = self.recorder
            declared.append(
                subscribe_raw(s, f"{keys.prefix}/**", lambda x: rec.record(x.key, x.payload))
            )
            declared.append(watch_liveliness(s, f"{keys.prefix}/**", rec.record_liveliness))
        declared += [
            watch_router_link(s, lambda up: presence.push((ROUTER_LINK, up))),
            watch_liveliness(s, keys.vehicles_alive_all, lambda k, a: presence.push((k, a))),
            subscribe(s, keys.vehicle_status_all, VehicleStatus, self.receive_status),
            subscribe_telemetry(s, keys, telemetry),
            subscribe(s, keys.vehicle_events_all, Event, lambda k, m: vehicle_events.push((k, m))),
            serve_async(
                s,
                keys.submit,
                SubmitRequest,
                self.on_submit,
                on_error=lambda e: SubmitReply(ok=False, error=e),
            ),
            serve_async_keyed(
                s,
                keys.submits_all,
                SubmitRequest,
                self.on_submit_as,
                on_error=lambda e: SubmitReply(ok=False, error=e),
            ),
            serve_async(
                s,
                keys.command,
                OperatorCommand,
                self.on_command,
                on_error=lambda e: CommandReply(ok=False, message=e.message, error=e),
            ),
            serve_async_keyed(
                s,
                keys.commands_all,
                OperatorCommand,
                self.on_command_as,
                on_error=lambda e: CommandReply(ok=False, message=e.message, error=e),
            ),
            *(
                serve_async(
                    s,
                    keys.report(vehicle.id),
                    AgentReport,
                    functools.partial(self.on_report, vehicle.id),
                    on_error=lambda e: CommandReply(ok=False, message=e.message, error=e),
                )
                for vehicle in self.show.vehicles
            ),
            serve_async(s, keys.snapshot, None, self.on_snapshot),
            serve(s, keys.clock, None, lambda _: clock_reply(self.clock)),  # on Zenoh's thread
            declare_token(s, keys.orchestrator_alive),
        ]
        self._spawn(self._follow_presence(presence))
        self._spawn(self._follow_status(statuses))
        self._spawn(self._follow_telemetry(telemetry))
        self._spawn(self._follow_vehicle_events(vehicle_events))
        self._spawn(self._timers())
        return declared

    async def run(self, stop: asyncio.Event) -> None:
        """Serve until ``stop`` is set; then undeclare everything and stop background work.

        Raises the database error that stopped the service, if one did.
        """
        self._stop = stop
        declared = self._declare()
        self.apply(self.book.tick(self.clock()))
        self._publish_fleet()  # viewers see the fleet at once, not a tick later
        log.info("orchestrator of %s ready", self.show.show_id)
        try:
            await stop.wait()
        finally:
            if self.fleet_changed:  # a change of the last tick is still told
                self._publish_fleet()
            for entity in reversed(declared):
                with contextlib.suppress(Exception):
                    entity.undeclare()
            for task in list(self._tasks):
                task.cancel()
            await asyncio.gather(*self._tasks, return_exceptions=True)
            self.estimates.shutdown()
        if self.fatal is not None:
            raise self.fatal

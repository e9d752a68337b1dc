"""Thin asyncio wiring of one vehicle agent to the bus: every decision is the JobRunner's.

Tasks of a running agent (one process, one event loop):

- control loop: at each tick ``runner.step`` -> backend mode command -> ``backend.tick``; telemetry
  and status published from what the runner says. A vehicle at rest (landed, no job, motors off)
  ticks only every ``rest_period_s`` when the settings allow it (a simulated vehicle: nothing
  moves; an autopilot keeps the full rate for its mocap and heartbeat streams); a command, an
  assignment or the orchestrator's presence changing wakes it at once;
- planning and metrics: the :class:`vehicle_agent.work.JobWork` (a planning worker process in
  ``skyquill agent``), awaited off the loop;
- reports: :class:`vehicle_agent.reports.ReportOutbox`;
- presence: the agent's liveliness token; the orchestrator's token watched and fed to the runner;
  the status heartbeat (:class:`vehicle_agent.heartbeat.StatusHeartbeat`): the status at least
  every ``status_period_s``, and something of its own (status or telemetry) at least every 1.1
  ``lost_after_s / 3`` (the orchestrator takes a silent vehicle as lost, token or not);
- the job lease (``vehicle_agent/lease.py``, held by :class:`vehicle_agent.job_guard.JobGuard`):
  before each tick, a job that may have been given to another vehicle (this agent stalled, its
  writing went unacknowledged, or the orchestrator said ``not_assigned``) is given up: brush
  lifted, back home;
- commands: the ``vehicles/<id>/command`` queryable answered by ``runner.handle_command``;
- events: what the vehicle says (autopilot STATUSTEXT, a refused take-off) published as Event on
  ``vehicles/<id>/events``, which the orchestrator relays into the show's event log.
- clock: this machine's wall clock measured against the orchestrator's on
  ``orchestrator/clock`` (:class:`vehicle_agent.clock_sync.ClockSync`), at start and about every
  ``clock_period_s``, into ``runner.clock_offset_s`` for the preflight and the status;
- stopping: :meth:`AgentService.land_then_stop` (the process's SIGTERM or SIGINT,
  ``vehicle_agent/stop_signals.py``) lands a vehicle in the air before the agent leaves the
  bus, as an operator's ``land`` does, and takes no job meanwhile.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import secrets
import time
from collections import deque
from collections.abc import Callable
from datetime import date

import msgspec

from bus.bridge import FifoChannel
from bus.keys import ShowKeys
from bus.messages import (
    AIRBORNE_STATES,
    CommandReply,
    ErrorInfo,
    JobAssignment,
    VehicleCommand,
    VehicleStatus,
)
from bus.pubsub import declare_token, publish, watch_liveliness
from bus.rpc import error_info_from_exception, serve_async
from bus.session import Session, open_session
from vehicle_agent.backend_step import step_backend
from vehicle_agent.backends.base import VehicleBackend, VehicleSnapshot
from vehicle_agent.battery import swap_battery, with_battery
from vehicle_agent.clock import TickClock
from vehicle_agent.clock_sync import ClockSample, ClockSync
from vehicle_agent.events import EventOutbox
from vehicle_agent.fault import clear_fault
from vehicle_agent.flight_day import FlightDay, with_day
from vehicle_agent.heartbeat import StatusHeartbeat
from vehicle_agent.job_end import job_result, measured_and_kept
from vehicle_agent.job_guard import JobGuard
from vehicle_agent.job_runner import JobRunner, PreparedJob, TickActions
from vehicle_agent.lease import JobLease
from vehicle_agent.pacer import OwnTimer, Pacer
from vehicle_agent.reports import ReportOutbox
from vehicle_agent.rest import at_rest
from vehicle_agent.results import ResultJournal
from vehicle_agent.runner_io import AbortedJob
from vehicle_agent.service_settings import ServiceSettings
from vehicle_agent.trace import JobTrace
from vehicle_agent.work import JobWork

log = logging.getLogger(__name__)

TICK_HISTORY = 4096
"""How many tick start times the service keeps (``AgentService.tick_starts_s``)."""
STOP_POLL_S = 0.05
"""How often in wall [s] a landing before the agent stops looks whether it is down."""


class AgentService:
    """One vehicle agent on the bus; ``await run(stop)`` until ``stop`` is set."""

    def __init__(
        self,
        settings: ServiceSettings,
        runner: JobRunner,
        backend: VehicleBackend,
        work: JobWork,
        events: EventOutbox | None = None,
        pacer: Pacer | None = None,
        wall_clock: Callable[[], float] = time.time,
    ) -> None:
        """``wall_clock``: the machine's clock (Unix time in [s]) compared with the
        orchestrator's (``vehicle_agent/clock_sync.py``); tests shift it."""
        self.settings = settings
        self.runner = runner
        self.backend = backend
        self.work = work
        """Plans, measures and records the jobs (closed when the service stops)."""
        self.keys = ShowKeys(settings.show_id)
        self.vehicle_id = runner.config.vehicle_id
        self.events = events if events is not None else EventOutbox(self.vehicle_id)
        """Events to publish; give its ``autopilot_text`` to the backend as ``on_text``."""
        self.clock = TickClock(
            period_s=backend.control_period_s,
            time_scale=settings.time_scale,
            skip_when_late=settings.skip_when_late,
        )
        self._prepared: dict[str, PreparedJob] = {}
        self.incarnation = secrets.token_hex(8)
        """This start of the vehicle's agent, on its statuses (``bus.messages.VehicleStatus``)."""
        self._tasks: set[asyncio.Task[None]] = set()
        self._lease = JobLease(settings.lost_after_s, time_scale=settings.time_scale)
        self.results = ResultJournal(self.vehicle_id, settings.results_dir)
        """Results of written jobs until the orchestrator has answered them."""
        self._guard = JobGuard(self._lease, runner, self.events, self.vehicle_id)
        self.reports = ReportOutbox(
            self.keys,
            self.vehicle_id,
            self._lease,
            retry_s=settings.report_retry_s,
            timeout_s=settings.report_timeout_s,
            running_job=lambda: self.runner.job_id,
            refused=self._guard.give_up,
            settled=self.results.settled,
        )
        self.pacer = pacer if pacer is not None else OwnTimer()
        """What the control loop waits on for its next tick (a fleet host's shared ticker)."""
        self._wake = asyncio.Event()
        self.resting = False
        """Whether the control loop is resting (ticking every ``rest_period_s``)."""
        self.tick_starts_s: deque[float] = deque(maxlen=TICK_HISTORY)
        """Wall (monotonic) times in [s] at which the latest ticks began: the loop's pace and
        period jitter, for measurements (``benchmarks/bench_agent.py``) and tests."""
        self._progress = 0.0
        self._snapshot: VehicleSnapshot | None = None
        self.flight = FlightDay()
        """The vehicle's time off the ground today, for its status."""
        self.clock_sync = ClockSync(
            self.keys, wall_clock=wall_clock, period_s=settings.clock_period_s
        )
        """Measures this machine's clock against the orchestrator's, for the preflight."""
        self.stopping = False
        """Whether the agent is about to stop (:meth:`land_then_stop`): it takes no job."""

    async def run(self, stop: asyncio.Event) -> None:
        """Join the bus, fly until ``stop`` is set, then leave it cleanly."""
        with open_session(self.settings.zenoh, role="client") as session:
            await self.serve(session, stop)

    async def serve(self, session: Session, stop: asyncio.Event) -> None:
        """Fly on ``session`` (this vehicle's own, opened with its identity) until ``stop`` is
        set; the caller closes the session afterwards, which takes the liveliness token away."""
        self._session = session
        for result in self.results.recover():  # written before a restart, never answered
            log.info("%s: job %s's result sent again", self.vehicle_id, result.job_id)
            self.reports.queue(result)
        declare_token(session, self.keys.vehicle_alive(self.vehicle_id))
        presence: FifoChannel[bool] = FifoChannel()
        watch_liveliness(
            session, self.keys.orchestrator_alive, lambda _key, alive: presence.push(alive)
        )
        serve_async(
            session,
            self.keys.vehicle_command(self.vehicle_id),
            VehicleCommand,
            self._on_command,
            on_error=_error_reply,
        )
        serve_async(
            session,
            self.keys.vehicle_assign(self.vehicle_id),
            VehicleCommand,
            self._on_assign,
            on_error=_error_reply,
        )
        self._heartbeat = StatusHeartbeat(
            session,
            self.keys.vehicle_status(self.vehicle_id),
            self.keys.telemetry(self.vehicle_id),
            self._status,
            status_period_s=self.settings.status_period_s,
            lost_after_s=self.settings.lost_after_s,
        )
        snapshot = await self.backend.start()
        log.info("vehicle %s ready on show %s", self.vehicle_id, self.settings.show_id)
        workers = [
            asyncio.create_task(self._control_loop(snapshot)),
            asyncio.create_task(self.reports.send_forever(session)),
            asyncio.create_task(self._follow_presence(presence)),
            asyncio.create_task(self._heartbeat.run()),
            asyncio.create_task(self.clock_sync.run(session, self._clock_measured)),
        ]
        stopping = asyncio.create_task(stop.wait())
        await asyncio.wait([stopping, *workers], return_when=asyncio.FIRST_COMPLETED)
        for task in [*workers, *self._tasks, stopping]:
            task.cancel()
        outcomes = await asyncio.gather(*workers, *self._tasks, return_exceptions=True)
        await self.backend.close()
        await self.work.close()
        for outcome in outcomes:
            if isinstance(outcome, Exception):
                raise outcome

    # --- inputs --------------------------------------------------------------------------------
    async def _on_command(self, command: VehicleCommand) -> CommandReply:
        """Commands anyone with the right to command vehicles may send (not ``assign``)."""
        if command.command == "assign":
            where = self.keys.vehicle_assign(self.vehicle_id)
            return _refusal("forbidden", f"jobs are assigned on {where} only", field="command")
        return await self._handle(command)

    async def _on_assign(self, command: VehicleCommand) -> CommandReply:
        """Job assignments: access control lets only the orchestrator query this key. A job this
        vehicle has just finished (its result not yet delivered: the orchestrator was away) is
        refused rather than written twice."""
        job = command.job
        if self.stopping:
            return _refusal("busy", f"{self.vehicle_id}'s agent is stopping")
        if job is not None and self.results.unsettled(job.job_id):
            return _refusal("busy", f"{job.job_id} was flown here; its result is on its way")
        if command.command != "assign":
            where = self.keys.vehicle_assign(self.vehicle_id)
            return _refusal("invalid", f"only assign is sent on {where}", field="command")
        return await self._handle(command)

    async def _handle(self, command: VehicleCommand) -> CommandReply:
        self._wake_up()
        if command.command == "clear_fault":
            return await self._clear_fault()
        if command.command == "battery_swapped":
            reply = await swap_battery(self.backend, self.vehicle_id)
            log.info("%s battery_swapped -> %s", self.vehicle_id, reply.message)
            return reply
        reply = self.runner.handle_command(command, self.clock.now_s)
        log.info("%s %s -> %s", self.vehicle_id, command.command, reply.message)
        self._heartbeat.publish_status()
        return reply

    async def _follow_presence(self, presence: FifoChannel[bool]) -> None:
        async for alive in presence:
            log.info("%s: orchestrator %s", self.vehicle_id, "present" if alive else "lost")
            self._wake_up()
            self.runner.set_orchestrator_alive(alive, self.clock.now_s)
            self._heartbeat.publish_status()

    # --- stopping ------------------------------------------------------------------------------
    def airborne(self) -> bool:
        """Whether the vehicle is off the ground or on its way there (its runner flies a job or a
        landing, or its backend says it is not on the ground); not after an emergency stop."""
        if self.runner.phase == "stopped":
            return False
        snapshot = self._snapshot
        return self.runner.state in AIRBORNE_STATES or (
            snapshot is not None and not snapshot.on_ground
        )

    async def land_then_stop(self, stop: asyncio.Event, limit_s: float) -> None:
        """Set ``stop`` once the vehicle is on the ground: at once when it is there, else after
        an operator's ``land`` (brush lifted, back home, down; the job abandoned for the
        orchestrator to take back, ``vehicle_agent/job_runner.py``), or after ``limit_s`` wall
        [s] when it has not landed by then (said in the log and the event log). No job is taken
        meanwhile."""
        self.stopping = True
        if not self.airborne():
            stop.set()
            return
        vid, started_s = self.vehicle_id, time.monotonic()
        said = f"{vid}: its agent is stopping; landing first (up to {limit_s:.0f} s)"
        log.warning("%s", said)
        self.events.push("warning", "stop_landing", said, job_id=self.runner.job_id)
        await self._handle(VehicleCommand(command="land"))
        while self.airborne():
            if time.monotonic() - started_s > limit_s:
                said = (
                    f"{vid} has not landed in {limit_s:.0f} s ({self.runner.state}: "
                    f"{self.runner.message}); its agent stops anyway: an autopilot falls back "
                    "on its own failsafe, a simulated vehicle stops where it is"
                )
                log.error("%s", said)
                self.events.push("alert", "stop_landing", said)
                break
            await asyncio.sleep(STOP_POLL_S)
        else:
            said = f"{vid} landed in {time.monotonic() - started_s:.1f} s; its agent stops"
            log.warning("%s", said)
            self.events.push("info", "stop_landing", said)
        for event in self.events.drain():  # said before the session closes
            publish(self._session, self.keys.vehicle_events(vid), event)
        stop.set()

    def _clock_measured(self, best: ClockSample) -> None:
        """The clock filter's best sample: the preflight checks it from the next tick on."""
        self.runner.clock_offset_s = best.offset_s

    async def _clear_fault(self) -> CommandReply:
        """The operator's ``clear_fault``: leave ``fault`` only when the vehicle is at rest."""
        if self._snapshot is None:
            reply = CommandReply(ok=False, message="the vehicle has not reported its state yet")
        else:
            reply = await clear_fault(self.runner, self._snapshot, self.backend)
        if reply.ok:
            self.events.push("info", "fault_cleared", reply.message)
        else:
            self.events.push("warning", "fault_kept", reply.message)
        log.info("%s clear_fault -> %s", self.vehicle_id, reply.message)
        self._heartbeat.publish_status()
        return reply

    # --- the control loop ----------------------------------------------------------------------
    async def _control_loop(self, snapshot: VehicleSnapshot) -> None:
        rest_period_s = self.settings.rest_period_s
        while True:
            if rest_period_s is not None and at_rest(self.runner, snapshot):
                await self._rest(rest_period_s)
            else:
                await self.pacer.wait_until(time.monotonic() + self.clock.delay_s())
            self.tick_starts_s.append(time.monotonic())
            now_s = self.clock.now_s
            wall_s = time.monotonic()
            stalled_s = self._heartbeat.take_stalled()
            probe = self._guard.before_tick(wall_s, stalled_s, self._progress)
            if probe is not None:
                self.reports.queue(probe)
            self.runner.may_begin_writing = self._lease.may_begin_writing(wall_s)
            actions = self.runner.step(snapshot, now_s)
            snapshot = await step_backend(
                self.backend, self.runner, self.events, actions, snapshot, now_s
            )
            self._snapshot = snapshot
            self.flight.tick(snapshot, now_s, date.today().toordinal())
            self.clock.advance()
            self._carry_out(actions)
            self._lease.tick_done(time.monotonic())

    async def _rest(self, period_s: float) -> None:
        """Wait for a wake-up or ``period_s``, whichever first; then the agent's clock is
        brought up to the wall clock (agent time goes on while resting)."""
        self.resting = True
        self._wake.clear()
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(self._wake.wait(), period_s)
        self._wake_up()
        self._lease.tick_done(time.monotonic())  # resting is no stall

    def _wake_up(self) -> None:
        """Something needs the loop: end a rest now (agent time caught up first, so that a
        command is handled at the right time)."""
        if self.resting:
            self.resting = False
            self.clock.catch_up()
            self._wake.set()

    def _carry_out(self, actions: TickActions) -> None:
        if actions.plan_request is not None:
            self._spawn(self._plan(actions.plan_request))
        for report in actions.reports:
            self.reports.queue(report)
        if actions.finished is not None:
            self.results.written(actions.finished.job_id, actions.finished.duration_s)
            self._spawn(self._finish(actions.finished))
        if (aborted := actions.aborted) is not None:
            if aborted.report is not None:  # kept from this tick: a restart still sends it
                self.results.measured(aborted.report)
            self._spawn(self._finish(aborted.trace, aborted))
        if actions.telemetry is not None:
            self._heartbeat.publish_telemetry(actions.telemetry)
            self._progress = actions.telemetry.progress
        for said in actions.events:
            self.events.push(said.level, said.kind, said.message, job_id=said.job_id)
        for event in self.events.drain():
            publish(self._session, self.keys.vehicle_events(self.vehicle_id), event)
        self._heartbeat.publish_status(only_if_changed=True)

    def _spawn(self, coro: object) -> None:
        task: asyncio.Task[None] = asyncio.create_task(coro)  # type: ignore[arg-type]
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    async def _plan(self, assignment: JobAssignment) -> None:
        try:
            prepared = await self.work.prepare(assignment)
        except Exception as exc:
            log.warning("%s: cannot plan job %s: %s", self.vehicle_id, assignment.job_id, exc)
            self.runner.plan_failed(assignment.job_id, error_info_from_exception(exc))
            return
        self._prepared = {assignment.job_id: prepared}
        self.runner.plan_ready(prepared)

    async def _finish(self, trace: JobTrace, aborted: AbortedJob | None = None) -> None:
        """Measure the flown job (``aborted``: broken off), record it, then report it: a job
        reported has its record on disk (its picture may still be drawn). From the tick its
        writing ended until the orchestrator answers, its result is in ``results`` and the
        status names the job; not an ``ended`` report (``vehicle_agent/end_reasons.py``): the
        job is no longer this vehicle's, and the report only says what was written of it."""
        prepared = self._prepared[trace.job_id]
        metrics = await measured_and_kept(self.work, prepared, trace, self.vehicle_id)
        writing = self.runner.safety.writing
        result = job_result(self.vehicle_id, prepared, trace, metrics, writing, aborted)
        if result.event != "ended":
            self.results.measured(result)
        self.reports.queue(result)

    # --- outputs -------------------------------------------------------------------------------
    def _status(self) -> VehicleStatus:
        """The status as it is now; a job whose result the orchestrator has not answered yet
        stays on it."""
        status = with_battery(self.runner.status(self.incarnation), self._snapshot)
        status = with_day(status, self._snapshot, self.flight)
        pending = self.results.pending() if status.job_id is None else None
        if pending is not None:  # not over until the orchestrator has its result
            status = msgspec.structs.replace(status, job_id=pending)
        return status


def _refusal(code: str, message: str, *, field: str | None = None) -> CommandReply:
    """A command the agent will not carry out, and why."""
    info = ErrorInfo(code=code, message=message, field=field)
    return CommandReply(ok=False, message=message, error=info)


def _error_reply(info: ErrorInfo) -> CommandReply:
    return CommandReply(ok=False, message=info.message, error=info)

"""The agent's asyncio wiring over real Zenoh (in one process), against a fake orchestrator."""

from __future__ import annotations

import asyncio
import threading
import time
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from dataclasses import replace
from pathlib import Path

from test_agent_job_runner import HOME, config, line_samples

from bus.keys import ShowKeys
from bus.messages import (
    AgentReport,
    CommandReply,
    Event,
    JobAssignment,
    JobMetrics,
    Telemetry,
    VehicleCommand,
    VehicleStatus,
)
from bus.pubsub import declare_token, subscribe
from bus.rpc import aquery_one, serve
from bus.session import BusSettings, Session, open_session
from vehicle_agent.backends.base import (
    BackendError,
    CommandRefusedError,
    Setpoint,
    Vec3,
    VehicleSnapshot,
)
from vehicle_agent.backends.kinematic import KinematicBackend
from vehicle_agent.events import EventOutbox
from vehicle_agent.job_runner import JobRunner, PreparedJob
from vehicle_agent.service import AgentService
from vehicle_agent.service_settings import ServiceSettings
from vehicle_agent.trace import JobTrace
from vehicle_agent.work import ThreadJobWork

SHOW = "agenttest"
KEYS = ShowKeys(SHOW)
METRICS = JobMetrics(
    rmse_pen_down_m=0.001, rmse_m=0.002, max_error_m=0.003, iou=0.9, duration_s=2.0
)


class FakeOrchestrator:
    """Presence token, a ``report`` queryable that records, and a way to command the vehicle."""

    def __init__(self, session: Session) -> None:
        self.session = session
        self.reports: list[AgentReport] = []
        self.telemetry: list[Telemetry] = []
        self.statuses: list[VehicleStatus] = []
        self._lock = threading.Lock()
        self.token = declare_token(session, KEYS.orchestrator_alive)
        self.queryable = serve(session, KEYS.report("uav1"), AgentReport, self._on_report)
        self.subscribers = [
            subscribe(
                session, KEYS.telemetry_all, Telemetry, lambda _k, m: self.telemetry.append(m)
            ),
            subscribe(
                session,
                KEYS.vehicle_status_all,
                VehicleStatus,
                lambda _k, m: self.statuses.append(m),
            ),
        ]

    def _on_report(self, report: AgentReport) -> CommandReply:
        with self._lock:
            self.reports.append(report)
        return CommandReply(ok=True)

    def events(self) -> list[str]:
        with self._lock:
            return [r.event for r in self.reports if r.event not in ("progress", "holding")]

    def holding_reports(self) -> list[AgentReport]:
        with self._lock:
            return [r for r in self.reports if r.event == "holding"]

    async def command(self, command: VehicleCommand) -> CommandReply:
        if command.command == "assign":
            key = KEYS.vehicle_assign("uav1")
        else:
            key = KEYS.vehicle_command("uav1")
        return await aquery_one(self.session, key, command, CommandReply, timeout_s=5.0)


async def wait_for(condition: Callable[[], bool], timeout_s: float = 20.0) -> None:
    async with asyncio.timeout(timeout_s):
        while not condition():
            await asyncio.sleep(0.02)


def prepare(assignment: JobAssignment) -> PreparedJob:
    if assignment.text == "bad":
        raise ValueError("cannot write that")
    return PreparedJob(assignment.job_id, line_samples(2.0))


def measure(prepared: PreparedJob, trace: JobTrace) -> JobMetrics:
    return METRICS


class RefusingBackend(KinematicBackend):
    """Refuses its first take-offs as an autopilot failing its pre-arm checks would (or fails)."""

    def __init__(self, error: BackendError, refusals: int = 1) -> None:
        super().__init__(HOME)
        self.error, self.refusals = error, refusals

    async def takeoff(self, hover_m_enu: Vec3) -> None:
        if self.refusals > 0:
            self.refusals -= 1
            raise self.error
        await super().takeoff(hover_m_enu)


class UnsettledBackend(KinematicBackend):
    """Says its autopilot's pre-arm checks fail while ``preflight`` is set (why)."""

    def __init__(self) -> None:
        super().__init__(HOME)
        self.preflight: str | None = None

    async def tick(self, setpoint: Setpoint | None, now_s: float) -> VehicleSnapshot:
        return replace(await super().tick(setpoint, now_s), preflight=self.preflight)


@asynccontextmanager
async def show(
    free_tcp_port: Callable[[], int],
    backend: KinematicBackend | None = None,
    rest_period_s: float | None = None,
) -> AsyncIterator[tuple[AgentService, FakeOrchestrator]]:
    endpoint = f"tcp/127.0.0.1:{free_tcp_port()}"
    bus = BusSettings(router_listen=[endpoint], connect=[endpoint])
    with open_session(bus, role="router"), open_session(bus, role="client") as orch_session:
        orchestrator = FakeOrchestrator(orch_session)
        settings = ServiceSettings(
            show_id=SHOW,
            zenoh=bus,
            time_scale=5.0,
            report_retry_s=0.1,
            rest_period_s=rest_period_s,
        )
        work = ThreadJobWork(prepare, measure)
        service = AgentService(
            settings, JobRunner(config()), backend or KinematicBackend(HOME), work
        )
        stop = asyncio.Event()
        task = asyncio.create_task(service.run(stop))
        try:
            await wait_for(lambda: service.runner.orchestrator_alive)
            yield service, orchestrator
        finally:
            stop.set()
            await asyncio.wait_for(task, 10.0)


def assign(job_id: str, text: str = "L") -> VehicleCommand:
    return VehicleCommand(command="assign", job=JobAssignment(job_id=job_id, text=text))


def test_a_job_is_flown_and_reported_with_telemetry_and_status(
    free_tcp_port: Callable[[], int],
) -> None:
    async def scenario() -> None:
        async with show(free_tcp_port) as (service, orch):
            reply = await orch.command(assign("j1"))
            assert reply.ok
            busy = await orch.command(assign("j2"))
            assert not busy.ok and busy.error is not None and busy.error.code == "busy"
            await wait_for(lambda: "done" in orch.events() and service.runner.state == "idle")
            assert orch.events() == ["started", "done"]
            # the lease is renewed before writing too: take-off and transit last > 0.5 s
            assert orch.holding_reports() and orch.reports[0].event == "holding"
            done = orch.reports[-1]
            assert done.metrics == METRICS and done.job_id == "j1"
            states = [s.state for s in orch.statuses]
            for state in ("taking_off", "writing", "returning", "landing"):
                assert state in states
            writing = [t for t in orch.telemetry if t.state == "writing"]
            assert writing and all(t.job_id == "j1" for t in writing)
            assert 0.0 < max(t.progress for t in writing) <= 1.0

    asyncio.run(scenario())


def ticks_within(service: AgentService, since_s: float) -> int:
    return sum(1 for t in service.tick_starts_s if t >= since_s)


def test_a_landed_idle_vehicle_rests_and_wakes_at_once_on_an_assignment(
    free_tcp_port: Callable[[], int],
) -> None:
    async def scenario() -> None:
        async with show(free_tcp_port, rest_period_s=0.5) as (service, orch):
            await wait_for(lambda: service.resting)
            since_s = time.monotonic()
            await asyncio.sleep(1.6)
            assert ticks_within(service, since_s) <= 5  # 100 Hz at time scale 5 would be 800
            telemetry_before = len(orch.telemetry)
            sent_s = time.monotonic()
            assert (await orch.command(assign("j1"))).ok
            await asyncio.sleep(1.0)  # woken: hundreds of ticks a second (resting: <= 3); 20 on
            assert ticks_within(service, sent_s) >= 20  # a loaded machine still tells them apart
            await wait_for(lambda: "done" in orch.events() and service.runner.state == "idle")
            assert orch.events() == ["started", "done"]
            await wait_for(lambda: service.resting)
            assert len(orch.telemetry) > telemetry_before
            # agent time went on while resting: about 5x the wall time since the start (a tick
            # clock that stopped while resting would be far behind; a loaded one lags a little)
            assert service.clock.now_s > 0.8 * 5.0 * (time.monotonic() - since_s)

    asyncio.run(scenario())


def test_a_vehicle_writes_on_while_the_orchestrator_is_away_and_reports_when_it_is_back(
    free_tcp_port: Callable[[], int],
) -> None:
    """The orchestrator's token and its report queryable go (it restarts) right after it has
    acknowledged the ready report and ``started``: the vehicle finishes the character on its
    write fence (``bus/fence.py``) and its ``done`` reaches the orchestrator once it is back."""

    async def scenario() -> None:
        async with show(free_tcp_port) as (service, orch):
            assert (await orch.command(assign("j1"))).ok
            await wait_for(lambda: service.runner.phase == "write" and "started" in orch.events())
            await asyncio.sleep(0.3)  # the acknowledgement is back at the agent
            orch.token.undeclare()
            orch.queryable.undeclare()  # type: ignore[no-untyped-call]
            await wait_for(lambda: service.runner.phase == "ground")
            assert service.runner.state == "idle"
            assert orch.events() == ["started"]  # its status names j1: the result is on its way
            orch.token = declare_token(orch.session, KEYS.orchestrator_alive)
            orch.queryable = serve(orch.session, KEYS.report("uav1"), AgentReport, orch._on_report)
            await wait_for(lambda: orch.events() == ["started", "done"])
            done = orch.reports[-1]
            assert done.metrics is not None and done.metrics.rmse_pen_down_m < 0.01

    asyncio.run(scenario())


def test_without_an_acknowledged_ready_report_the_vehicle_never_writes_and_gives_up(
    free_tcp_port: Callable[[], int],
) -> None:
    """The orchestrator goes before the vehicle reached the start of its writing: nobody
    acknowledges its ready report, so the brush never goes down and the vehicle gives the job
    up (brush lifted, home) once unheard for ``unheard_before_writing_s``."""

    async def scenario() -> None:
        async with show(free_tcp_port) as (service, orch):
            assert (await orch.command(assign("j1"))).ok
            await wait_for(lambda: service.runner.phase in ("transit", "settle"))
            orch.token.undeclare()
            orch.queryable.undeclare()  # type: ignore[no-untyped-call]
            await wait_for(lambda: service.runner.job_id is None)
            assert service.runner.state in ("returning", "landing", "idle")
            assert "gave j1 up" in service.runner.message or service.runner.state == "idle"

    asyncio.run(scenario())


def test_reports_are_retried_until_acknowledged_and_plan_errors_reported(
    free_tcp_port: Callable[[], int],
) -> None:
    async def scenario() -> None:
        async with show(free_tcp_port) as (service, orch):
            orch.queryable.undeclare()  # type: ignore[no-untyped-call]
            assert (await orch.command(assign("j1", text="bad"))).ok
            await wait_for(lambda: service.runner.state == "idle" and service.runner.job_id is None)
            await asyncio.sleep(0.3)
            assert orch.reports == []
            orch.queryable = serve(orch.session, KEYS.report("uav1"), AgentReport, orch._on_report)
            await wait_for(lambda: orch.events() == ["failed"])
            error = orch.reports[0].error
            assert error is not None and "cannot write that" in error.message

    asyncio.run(scenario())


def test_a_refused_takeoff_hands_the_job_back_and_is_told_on_the_events_key(
    free_tcp_port: Callable[[], int],
) -> None:
    refusal = CommandRefusedError("autopilot refused arming: PreArm: Compass not calibrated")

    async def scenario() -> None:
        async with show(free_tcp_port, RefusingBackend(refusal)) as (service, orch):
            events: list[Event] = []
            subscribe(
                orch.session, KEYS.vehicle_events("uav1"), Event, lambda _k, m: events.append(m)
            )
            assert (await orch.command(assign("j1"))).ok
            await wait_for(lambda: orch.events() == ["failed"] and bool(events))
            report = orch.reports[0]
            assert report.retry_after_s == 5.0 and report.error is not None
            assert report.error.code == "takeoff_refused" and "Compass" in report.error.message
            assert (events[0].kind, events[0].level, events[0].job_id) == (
                "takeoff_refused",
                "warning",
                "j1",
            )
            assert service.runner.state == "idle" and service.runner.job_id is None
            busy = await orch.command(assign("j2"))  # backing off: 5 s of agent time
            assert not busy.ok and busy.error is not None and busy.error.code == "takeoff_refused"

    asyncio.run(scenario())


def test_pre_arm_checks_are_published_in_the_status_with_an_event_as_they_fail_and_pass(
    free_tcp_port: Callable[[], int],
) -> None:
    why = "Preflight Fail: horizontal velocity unstable"

    async def scenario() -> None:
        backend = UnsettledBackend()
        async with show(free_tcp_port, backend) as (_service, orch):
            events: list[Event] = []
            subscribe(
                orch.session, KEYS.vehicle_events("uav1"), Event, lambda _k, m: events.append(m)
            )
            await asyncio.sleep(0.2)  # the subscriber is in place
            backend.preflight = why
            await wait_for(lambda: any(s.preflight == why for s in orch.statuses))
            await asyncio.sleep(0.3)
            backend.preflight = None
            await wait_for(lambda: orch.statuses[-1].preflight == "")  # published on change
            await wait_for(lambda: any("passes after" in e.message for e in events))
            said = [(e.level, e.message) for e in events if e.kind == "preflight"]
            assert said[0] == ("warning", f"uav1 held by its preflight: {why}")
            assert said[1][0] == "info" and len(said) == 2  # one each, not one per tick
            assert said[1][1].startswith("uav1 preflight passes after ")

    asyncio.run(scenario())


def test_any_other_takeoff_error_is_a_fault(free_tcp_port: Callable[[], int]) -> None:
    async def scenario() -> None:
        async with show(free_tcp_port, RefusingBackend(BackendError("lost link"))) as (
            service,
            orch,
        ):
            assert (await orch.command(assign("j1"))).ok
            await wait_for(lambda: service.runner.state == "fault")
            assert "lost link" in service.runner.message
            await wait_for(lambda: orch.events() == ["ended"])  # no result: nothing written
            (ended,) = [r for r in orch.reports if r.event == "ended"]
            assert ended.progress == 0.0 and ended.metrics is None and ended.error is not None
            assert ended.error.code == "vehicle_fault"

    asyncio.run(scenario())


def test_autopilot_texts_become_events_without_repeats() -> None:
    now = [100.0]
    outbox = EventOutbox("uav1", clock=lambda: now[0], repeat_after_s=10.0)
    outbox.autopilot_text(2, "PreArm: Need Position Estimate")  # MAV_SEVERITY_CRITICAL
    outbox.autopilot_text(4, "EKF3 IMU0 is using GPS")  # WARNING
    outbox.autopilot_text(6, "Arming motors")  # INFO
    outbox.autopilot_text(7, "debug chatter")  # DEBUG: dropped
    outbox.autopilot_text(2, "PreArm: Need Position Estimate")  # repeated at once: dropped
    drained = outbox.drain()
    assert [e.level for e in drained] == ["alert", "warning", "info"]
    assert drained[0].message == "uav1 autopilot: PreArm: Need Position Estimate"
    assert all(e.vehicle_id == "uav1" and e.time_s == 100.0 for e in drained)
    assert outbox.drain() == []
    now[0] = 111.0
    outbox.autopilot_text(2, "PreArm: Need Position Estimate")  # said again later: kept
    assert len(outbox.drain()) == 1


def test_a_result_unheard_when_its_agent_stops_is_sent_by_the_next_one(
    free_tcp_port: Callable[[], int], tmp_path: Path
) -> None:
    """The orchestrator is away when uav1 finishes j1; its agent then stops (as a kill would:
    the result is in its journal on disk, ``vehicle_agent/results.py``). The next agent of uav1
    names j1 in its status from its first one and sends the result once the orchestrator is
    back; then the journal is empty. A fresh agent without a journal would have said nothing of
    j1, and the orchestrator would have given it to another vehicle: written twice."""
    endpoint = f"tcp/127.0.0.1:{free_tcp_port()}"
    bus = BusSettings(router_listen=[endpoint], connect=[endpoint])
    settings = ServiceSettings(
        show_id=SHOW, zenoh=bus, time_scale=5.0, report_retry_s=0.1, results_dir=tmp_path
    )

    def agent() -> AgentService:
        work = ThreadJobWork(prepare, measure)
        return AgentService(settings, JobRunner(config()), KinematicBackend(HOME), work)

    async def scenario(orch: FakeOrchestrator) -> None:
        first, stop = agent(), asyncio.Event()
        running = asyncio.create_task(first.run(stop))
        await wait_for(lambda: first.runner.orchestrator_alive)
        assert (await orch.command(assign("j1"))).ok
        await wait_for(lambda: first.runner.phase == "write" and "started" in orch.events())
        await asyncio.sleep(0.3)  # the acknowledgement is back at the agent
        orch.queryable.undeclare()  # type: ignore[no-untyped-call]
        await wait_for(lambda: first.runner.phase == "ground" and first.results.pending() == "j1")
        stop.set()
        await asyncio.wait_for(running, 10.0)
        assert [p.name for p in tmp_path.iterdir()] == ["j1.json"]
        statuses_before = len(orch.statuses)
        second, stop = agent(), asyncio.Event()
        running = asyncio.create_task(second.run(stop))
        try:
            await wait_for(lambda: len(orch.statuses) > statuses_before)
            assert all(s.job_id == "j1" for s in orch.statuses[statuses_before:])
            assert second.incarnation != first.incarnation
            orch.queryable = serve(orch.session, KEYS.report("uav1"), AgentReport, orch._on_report)
            await wait_for(lambda: orch.events() == ["started", "done"])
            assert orch.reports[-1].metrics == METRICS
            await wait_for(lambda: not list(tmp_path.iterdir()))
            await wait_for(lambda: orch.statuses[-1].job_id is None)
        finally:
            stop.set()
            await asyncio.wait_for(running, 10.0)

    with open_session(bus, role="router"), open_session(bus, role="client") as orch_session:
        asyncio.run(scenario(FakeOrchestrator(orch_session)))

"""An agent asked to stop (SIGTERM, SIGINT) lands its vehicle first and takes no job meanwhile; a
second signal, or ``NOW_SIGNAL``, stops it at once; a vehicle that does not land in time is left
after the bound, said as an alert (issue 34). Real Zenoh in one process, real signals."""

from __future__ import annotations

import asyncio
import os
import signal
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager

from test_agent_job_runner import HOME, config
from test_agent_service import KEYS, SHOW, FakeOrchestrator, assign, measure, prepare, wait_for

from bus.messages import Event
from bus.pubsub import subscribe
from bus.session import BusSettings, open_session
from vehicle_agent.backends.kinematic import KinematicBackend
from vehicle_agent.job_runner import JobRunner
from vehicle_agent.service import AgentService
from vehicle_agent.service_settings import ServiceSettings
from vehicle_agent.stop_signals import NOW_SIGNAL, run_landing_first
from vehicle_agent.work import ThreadJobWork


class NeverLands(KinematicBackend):
    """An autopilot that takes the land command and stays where it is."""

    async def land(self) -> None:
        return None


@asynccontextmanager
async def agent(
    free_tcp_port: Callable[[], int], backend: KinematicBackend | None = None
) -> AsyncIterator[tuple[AgentService, FakeOrchestrator, list[Event]]]:
    """An agent service (not running) beside a fake orchestrator that records events too."""
    endpoint = f"tcp/127.0.0.1:{free_tcp_port()}"
    bus = BusSettings(router_listen=[endpoint], connect=[endpoint])
    with open_session(bus, role="router"), open_session(bus, role="client") as orch_session:
        orchestrator = FakeOrchestrator(orch_session)
        events: list[Event] = []
        orchestrator.subscribers.append(  # kept alive with the orchestrator
            subscribe(orch_session, KEYS.vehicle_events_all, Event, lambda _k, e: events.append(e))
        )
        settings = ServiceSettings(show_id=SHOW, zenoh=bus, time_scale=5.0, report_retry_s=0.1)
        work = ThreadJobWork(prepare, measure)
        backend = backend or KinematicBackend(HOME)
        yield AgentService(settings, JobRunner(config()), backend, work), orchestrator, events


def stop_landing(events: list[Event]) -> list[Event]:
    """The events an agent says about landing before it stops, in the order they came."""
    return [e for e in events if e.kind == "stop_landing"]


async def writing(service: AgentService, orch: FakeOrchestrator) -> None:
    assert (await orch.command(assign("j1"))).ok
    await wait_for(lambda: service.runner.phase == "write")


def test_a_stop_lands_a_writing_vehicle_first_and_refuses_jobs_meanwhile(
    free_tcp_port: Callable[[], int],
) -> None:
    async def scenario() -> None:
        async with agent(free_tcp_port) as (service, orch, events):
            stop = asyncio.Event()
            running = asyncio.create_task(service.run(stop))
            await wait_for(lambda: service.runner.orchestrator_alive)
            await writing(service, orch)
            landing = asyncio.create_task(service.land_then_stop(stop, limit_s=30.0))
            await wait_for(lambda: service.runner.state == "returning")
            refused = await orch.command(assign("j2"))
            assert not refused.ok and "stopping" in refused.message
            await asyncio.wait_for(stop.wait(), 30.0)
            assert service.runner.state == "landed" and service.runner.phase == "ground"
            snapshot = service._snapshot
            assert snapshot is not None and snapshot.on_ground
            assert snapshot.position_m_enu[2] == HOME[2]
            assert service.runner.job_id is None  # abandoned: the orchestrator takes it back
            await landing
            await asyncio.wait_for(running, 10.0)
            await wait_for(lambda: len(stop_landing(events)) >= 2, 5.0)  # the bus is asynchronous
            said = [e.message for e in stop_landing(events)]
            assert len(said) == 2 and "landing first" in said[0] and "landed in" in said[1]
            assert "done" not in orch.events()  # the character was not finished

    asyncio.run(scenario())


def test_a_stop_on_the_ground_is_at_once(free_tcp_port: Callable[[], int]) -> None:
    async def scenario() -> None:
        async with agent(free_tcp_port) as (service, _orch, _events):
            stop = asyncio.Event()
            running = asyncio.create_task(service.run(stop))
            await wait_for(lambda: service._snapshot is not None)
            await service.land_then_stop(stop, limit_s=30.0)
            assert stop.is_set() and service.runner.state == "idle"
            await asyncio.wait_for(running, 10.0)

    asyncio.run(scenario())


def test_a_vehicle_that_does_not_land_is_left_after_the_bound_with_an_alert(
    free_tcp_port: Callable[[], int],
) -> None:
    async def scenario() -> None:
        async with agent(free_tcp_port, NeverLands(HOME)) as (service, orch, events):
            stop = asyncio.Event()
            running = asyncio.create_task(service.run(stop))
            await wait_for(lambda: service.runner.orchestrator_alive)
            await writing(service, orch)
            started = asyncio.get_running_loop().time()
            await service.land_then_stop(stop, limit_s=3.0)
            waited_s = asyncio.get_running_loop().time() - started
            assert stop.is_set() and 3.0 <= waited_s < 6.0
            assert service.airborne()
            await asyncio.wait_for(running, 10.0)
            await wait_for(lambda: len(stop_landing(events)) >= 2, 5.0)  # the bus is asynchronous
            alerts = [e for e in stop_landing(events) if e.level == "alert"]
            assert alerts and "has not landed in 3 s" in alerts[0].message

    asyncio.run(scenario())


def test_sigterm_lands_first_and_the_now_signal_stops_at_once(
    free_tcp_port: Callable[[], int],
) -> None:
    """The process's own signals, as ``skyquill down`` and a supervisor send them."""

    async def scenario() -> None:
        async with agent(free_tcp_port, NeverLands(HOME)) as (service, orch, _events):
            running = asyncio.create_task(run_landing_first(service, limit_s=60.0))
            await wait_for(lambda: service.runner.orchestrator_alive)
            await writing(service, orch)
            os.kill(os.getpid(), signal.SIGTERM)
            await wait_for(lambda: service.stopping)
            await asyncio.sleep(0.5)
            assert not running.done()  # still trying to land (this one never does)
            os.kill(os.getpid(), NOW_SIGNAL)
            await asyncio.wait_for(running, 10.0)
            assert service.airborne()  # left where it was: it was asked to

    asyncio.run(scenario())


def test_a_second_sigterm_stops_at_once(free_tcp_port: Callable[[], int]) -> None:
    async def scenario() -> None:
        async with agent(free_tcp_port, NeverLands(HOME)) as (service, orch, _events):
            running = asyncio.create_task(run_landing_first(service, limit_s=60.0))
            await wait_for(lambda: service.runner.orchestrator_alive)
            await writing(service, orch)
            os.kill(os.getpid(), signal.SIGTERM)
            await wait_for(lambda: service.stopping)
            os.kill(os.getpid(), signal.SIGINT)
            await asyncio.wait_for(running, 10.0)

    asyncio.run(scenario())

"""Clocks over a real secured bus (issue 32, preflight and health): the show's own CA and
certificates, its router in this process with the generated access control, the orchestrator in a
thread, and two simulated vehicles' agents, each with its own identity: uav1 on a wall clock
200 ms ahead (injected; the machine's clock is not touched), uav2 on the machine's own."""

from __future__ import annotations

import asyncio
import re
import threading
import time
from collections.abc import Iterator
from dataclasses import replace

import pytest
from test_agent_service import wait_for
from test_orchestrator_service import RunningOrchestrator, make_show

from bus.keys import ShowKeys
from bus.messages import ClockReply, Event, JobAssignment, JobMetrics, ShowSnapshot
from bus.pubsub import subscribe
from bus.rpc import aquery_one, query, query_one
from bus.session import Session, free_tcp_endpoint, open_session
from showfile import SecuritySettings, Show
from trust.settings import ensure_show_keys, session_settings
from vehicle_agent.agent import make_backend, make_runner, service_settings
from vehicle_agent.job_runner import PreparedJob
from vehicle_agent.service import AgentService
from vehicle_agent.setup import vehicle_setup
from vehicle_agent.trace import JobTrace
from vehicle_agent.work import ThreadJobWork

pytestmark = [pytest.mark.slow, pytest.mark.timeout(120)]

SHIFT_S = 0.2
"""How far uav1's wall clock runs ahead of the machine's, [s]."""
HELD = re.compile(
    r"clock: \+(19[5-9]|20[0-5]) ms off the orchestrator's \(limit 50 ms\): "
    r"synchronise it \(NTP/PTP\)"
)


@pytest.fixture(scope="module")
def secured(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Show]:
    """A secured show with its keys, its router in this process and its orchestrator running."""
    tmp = tmp_path_factory.mktemp("clocks")
    _, show = make_show(
        tmp,
        "clocks",
        free_tcp_endpoint(),
        security=SecuritySettings(mode="mtls", keys_dir=tmp / "keys"),
    )
    ensure_show_keys(show)
    with open_session(session_settings(show, "router"), role="router"), RunningOrchestrator(show):
        yield show


def _as(show: Show, identity: str) -> Session:
    return open_session(session_settings(show, identity), role="client", open_timeout_s=10.0)


def _no_job(assignment: JobAssignment) -> PreparedJob:
    raise AssertionError(f"no job is submitted here, got {assignment.job_id}")


def _no_metrics(prepared: PreparedJob, trace: JobTrace) -> JobMetrics:
    raise AssertionError("no job is written here")


def _agent(show: Show, vehicle_id: str, shift_s: float) -> AgentService:
    """A simulated vehicle's agent on its own identity, measuring its clock every 0.5 s."""
    setup = vehicle_setup(show, vehicle_id)
    settings = replace(service_settings(setup), clock_period_s=0.5, results_dir=None)
    return AgentService(
        settings,
        make_runner(setup),
        make_backend(setup),
        ThreadJobWork(_no_job, _no_metrics),
        wall_clock=lambda: time.time() + shift_s,
    )


def test_an_agent_whose_clock_is_200_ms_ahead_is_held_and_the_orchestrator_alerts_once(
    secured: Show,
) -> None:
    keys = ShowKeys(secured.show_id)
    events: list[Event] = []
    lock = threading.Lock()

    def heard(_key: str, event: Event) -> None:
        with lock:
            events.append(event)

    async def scenario(console: Session) -> ShowSnapshot:
        ahead, right = _agent(secured, "uav1", SHIFT_S), _agent(secured, "uav2", 0.0)
        stop = asyncio.Event()
        tasks = [asyncio.create_task(agent.run(stop)) for agent in (ahead, right)]
        try:
            await wait_for(
                lambda: (
                    ahead.runner.preflight is not None and right.runner.clock_offset_s is not None
                ),
                timeout_s=30.0,
            )
            assert HELD.fullmatch(str(ahead.runner.preflight)), ahead.runner.preflight
            await asyncio.sleep(4.0)  # eight exchanges more each, four statuses: still one alert
            assert ahead.runner.clock_offset_s == pytest.approx(SHIFT_S, abs=0.005)
            assert right.runner.clock_offset_s == pytest.approx(0.0, abs=0.005)
            assert HELD.fullmatch(str(ahead.runner.preflight)), ahead.runner.preflight
            assert right.runner.preflight is None  # nothing else holds a simulated vehicle
            return await aquery_one(console, keys.snapshot, None, ShowSnapshot, timeout_s=5.0)
        finally:
            stop.set()
            await asyncio.wait_for(asyncio.gather(*tasks), 15.0)

    with _as(secured, "operator") as console:
        subscriber = subscribe(console, keys.events, Event, heard)
        snap = asyncio.run(scenario(console))
        subscriber.undeclare()  # type: ignore[no-untyped-call]
    vehicles = {v.vehicle_id: v for v in snap.vehicles}
    assert HELD.fullmatch(vehicles["uav1"].preflight), vehicles["uav1"]
    assert vehicles["uav1"].message.startswith("held by its preflight: clock: +")
    assert vehicles["uav2"].alive and vehicles["uav2"].preflight == ""
    with lock:
        alerts = [e for e in events if e.kind == "clock_offset"]
    assert [(e.level, e.vehicle_id) for e in alerts] == [("alert", "uav1")], alerts
    assert re.fullmatch(
        r"uav1 clock \+(19[5-9]|20[0-5]) ms off the orchestrator's \(limit 50 ms\): held by its "
        r"preflight; synchronise its clock \(NTP/PTP\)",
        alerts[0].message,
    )
    assert [(a.kind, a.vehicle_id) for a in snap.alerts if a.kind == "clock_offset"] == [
        ("clock_offset", "uav1")
    ]


def test_a_vehicle_may_ask_the_orchestrators_clock_and_the_kiosk_may_not(secured: Show) -> None:
    keys = ShowKeys(secured.show_id)
    with _as(secured, "uav3") as vehicle, _as(secured, "kiosk") as kiosk:
        deadline = time.monotonic() + 10.0
        while not query(vehicle, keys.clock, None, ClockReply):
            assert time.monotonic() < deadline, "the orchestrator does not answer uav3"
        before_s = time.time()
        reply = query_one(vehicle, keys.clock, None, ClockReply, timeout_s=5.0)
        assert before_s - 0.01 <= reply.receive_s <= reply.transmit_s <= time.time() + 0.01
        assert (
            query(kiosk, keys.clock, None, ClockReply, timeout_s=1.5) == []
        )  # the router drops it

"""A fleet host (several simulated vehicles' agents in one process) on a real, secured show.

The router and the real orchestrator run as supervised children; the fleet host runs in a thread
of this process, so that the tests can reach each vehicle's own session. Each vehicle must stay a
vehicle of its own on the bus: its jobs written through the orchestrator, its liveliness its own,
its access-control rights only its own.
"""

from __future__ import annotations

import asyncio
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from bus.keys import ShowKeys
from bus.messages import VehicleStatus
from bus.pubsub import alive_keys, publish, subscribe
from bus.rpc import NoReplyError, RemoteError
from bus.session import Session, open_session
from cli.fleets import split_fleets
from cli.showrun import derived_show, snapshot, submit_texts, wait_for_jobs
from cli.supervisor import Supervisor, child_env, fleet_stop_grace_s, show_children
from showfile import Show, load_show
from trust.settings import ensure_show_keys, session_settings
from vehicle_agent.fleet import FleetHost

pytestmark = [pytest.mark.multiprocess, pytest.mark.slow, pytest.mark.timeout(120)]

AIRSHOW = Path(__file__).resolve().parent.parent / "shows" / "airshow-2014.yaml"
TIME_SCALE = 6.0
FLEET = ("uav1", "uav2", "uav3")


@dataclass
class LiveFleet:
    show: Show
    keys: ShowKeys
    host: FleetHost
    loop: asyncio.AbstractEventLoop
    operator: Session


def _fleet_thread(host: FleetHost, ready: threading.Event, out: dict[str, object]) -> None:
    async def main() -> None:
        stop = asyncio.Event()
        out["loop"], out["stop"] = asyncio.get_running_loop(), stop
        ready.set()
        await host.run(stop)

    asyncio.run(main())


def _wait_ready(operator: Session, keys: ShowKeys, vehicle_ids: tuple[str, ...]) -> None:
    deadline = time.monotonic() + 60.0
    while time.monotonic() < deadline:
        try:
            vehicles = {v.vehicle_id: v for v in snapshot(operator, keys, timeout_s=2.0).vehicles}
        except (NoReplyError, RemoteError):
            vehicles = {}
        if all(v in vehicles and vehicles[v].alive for v in vehicle_ids):
            return
        time.sleep(0.2)
    raise AssertionError("the fleet's vehicles did not join the show")


@pytest.fixture(scope="module")
def live(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LiveFleet]:
    out = tmp_path_factory.mktemp("fleet")
    base = load_show(AIRSHOW)
    path, show = derived_show(AIRSHOW, out, time_scale=TIME_SCALE, vehicles=base.vehicles[:3])
    assert show.security.mode == "mtls"
    ensure_show_keys(show)
    specs = show_children(path, [], log_dir=out / "logs")  # router and orchestrator only
    supervisor = Supervisor(specs, env=child_env())
    supervisor.start()
    host = FleetHost(show, FLEET, workers=1)
    ready, handles = threading.Event(), dict[str, object]()
    thread = threading.Thread(target=_fleet_thread, args=(host, ready, handles), daemon=True)
    thread.start()
    ready.wait()
    loop = handles["loop"]
    assert isinstance(loop, asyncio.AbstractEventLoop)
    try:
        settings = session_settings(show, "operator")
        with open_session(settings, role="client", open_timeout_s=30.0) as operator:
            keys = ShowKeys(show.show_id)
            _wait_ready(operator, keys, FLEET)
            yield LiveFleet(show, keys, host, loop, operator)
    finally:
        stop = handles["stop"]
        assert isinstance(stop, asyncio.Event)
        loop.call_soon_threadsafe(stop.set)
        thread.join(timeout=30.0)
        supervisor.stop()
    assert not thread.is_alive(), "the fleet host did not stop"


def test_the_fleets_vehicles_write_jobs_from_the_real_orchestrator(live: LiveFleet) -> None:
    replies = submit_texts(live.operator, live.keys, ["一", "L", "十"])
    job_ids = [str(reply.job_id) for reply in replies]
    jobs = wait_for_jobs(live.operator, live.keys, job_ids, timeout_s=90.0)
    assert [j.state for j in jobs] == ["done"] * 3, [(j.label, j.state, j.error) for j in jobs]
    assert {j.vehicle_id for j in jobs} <= set(FLEET)
    assert all(j.metrics is not None and j.metrics.rmse_pen_down_m < 0.02 for j in jobs)
    assert len(live.host.tickers) == 1  # one timer stepped every vehicle's loop
    assert live.host.pool.requests >= 3 * 3  # planned, measured and recorded by the shared pool


def test_a_vehicle_of_the_fleet_cannot_speak_or_live_for_another(live: LiveFleet) -> None:
    seen: list[VehicleStatus] = []
    key = live.keys.vehicle_status("uav2")
    subscriber = subscribe(live.operator, key, VehicleStatus, lambda _k, s: seen.append(s))
    forged = VehicleStatus(vehicle_id="uav2", kind="quadrotor-brush", state="fault")
    uav1 = live.host.sessions["uav1"]
    publish(uav1, live.keys.vehicle_status("uav2"), forged)
    token = uav1.liveliness().declare_token(live.keys.vehicle_alive("ghost"))
    deadline = time.monotonic() + 30.0
    while not seen:  # uav2's own statuses arrive (a loaded machine is slow)...
        assert time.monotonic() < deadline, "uav2's statuses did not arrive"
        time.sleep(0.1)
    time.sleep(1.0)  # ...and the forged one would have by now
    alive = alive_keys(live.operator, live.keys.vehicles_alive_all, timeout_s=2.0)
    token.undeclare()  # type: ignore[no-untyped-call]
    subscriber.undeclare()  # type: ignore[no-untyped-call]
    assert seen and not any(status.state == "fault" for status in seen), seen
    assert live.keys.vehicle_alive("ghost") not in alive
    assert {live.keys.vehicle_alive(v) for v in FLEET} <= alive


def test_a_vehicle_whose_agent_fails_is_started_again_alone(live: LiveFleet) -> None:
    failing = live.host.services["uav2"]

    def broken(*_args: object) -> None:
        raise RuntimeError("a bug in one vehicle's agent")

    def break_it() -> None:  # its next tick fails (a resting vehicle ticks every second)
        failing.runner.step = broken  # type: ignore[method-assign, assignment]

    live.loop.call_soon_threadsafe(break_it)
    deadline = time.monotonic() + 15.0
    while live.host.services["uav2"] is failing or "uav2" not in live.host.sessions:
        assert time.monotonic() < deadline, "uav2 was not started again"
        time.sleep(0.1)
    assert live.host.restarts == {"uav1": 0, "uav2": 1, "uav3": 0}
    while live.keys.vehicle_alive("uav2") not in alive_keys(
        live.operator, live.keys.vehicles_alive_all
    ):
        assert time.monotonic() < deadline, "uav2 did not come back on the bus"
        time.sleep(0.1)


def test_one_vehicle_taken_off_the_bus_is_the_only_one_lost(live: LiveFleet) -> None:
    live.loop.call_soon_threadsafe(live.host.stop_vehicle, "uav3")
    deadline = time.monotonic() + 15.0
    while True:
        vehicles = {v.vehicle_id: v.alive for v in snapshot(live.operator, live.keys).vehicles}
        if not vehicles.get("uav3", True):
            break
        assert time.monotonic() < deadline, vehicles
        time.sleep(0.2)
    assert vehicles["uav1"] and vehicles["uav2"], vehicles
    alive = alive_keys(live.operator, live.keys.vehicles_alive_all, timeout_s=2.0)
    assert alive == {live.keys.vehicle_alive(v) for v in ("uav1", "uav2")}


def test_up_puts_simulated_vehicles_in_fleet_hosts_and_real_ones_apart(tmp_path: Path) -> None:
    base = load_show(AIRSHOW)
    real = base.vehicles[3].model_copy(update={"backend": "mavlink", "mavlink_url": "udpin:x:1"})
    _, show = derived_show(AIRSHOW, tmp_path, vehicles=(*base.vehicles[:3], real), fleet_hosts=2)
    alone, fleets = split_fleets(show, [v.id for v in show.vehicles])
    assert alone == ("uav4",) and fleets == (("uav1", "uav3"), ("uav2",))
    specs = show_children(Path("s.yaml"), alone, fleets=fleets, time_scale=2.0)
    fleet = {s.name: s for s in specs}["fleet 1"]
    assert fleet.argv[-5:] == ("s.yaml", "--vehicles", "uav1,uav3", "--time-scale", "2.0")
    assert fleet.stop_grace_s == fleet_stop_grace_s(2)
    assert "agent uav4" in {s.name for s in specs}


def test_a_real_vehicle_is_refused_by_the_fleet_command(tmp_path: Path) -> None:
    base = load_show(AIRSHOW)
    real = base.vehicles[1].model_copy(update={"backend": "mavlink", "mavlink_url": "udpin:x:1"})
    path, _ = derived_show(AIRSHOW, tmp_path, vehicles=(base.vehicles[0], real))
    argv = [sys.executable, "-m", "cli.main", "fleet", str(path), "--vehicles", "uav1,uav2"]
    done = subprocess.run(argv, env=child_env(), capture_output=True, text=True, timeout=30)
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "uav2 has backend mavlink" in lines[0], done.stderr


def test_a_fleet_process_joins_as_its_vehicles_and_stops_in_its_grace(tmp_path: Path) -> None:
    base = load_show(AIRSHOW)
    path, show = derived_show(AIRSHOW, tmp_path, vehicles=base.vehicles[:2], fleet_hosts=1)
    ensure_show_keys(show)
    alone, fleets = split_fleets(show, [v.id for v in show.vehicles])
    specs = show_children(path, alone, fleets=fleets, services=False, log_dir=tmp_path / "logs")
    assert [s.name for s in specs] == ["router", "fleet 1"]
    supervisor = Supervisor(specs, env=child_env())
    supervisor.start()
    try:
        keys = ShowKeys(show.show_id)
        wanted = {keys.vehicle_alive(v) for v in ("uav1", "uav2")}
        settings = session_settings(show, "operator")
        with open_session(settings, role="client", open_timeout_s=30.0) as operator:
            deadline = time.monotonic() + 30.0
            while alive_keys(operator, keys.vehicles_alive_all) != wanted:
                assert time.monotonic() < deadline, "the fleet's vehicles did not join"
                time.sleep(0.2)
    finally:
        report = supervisor.stop()
    assert report.killed == [] and report.slow == [], report.summary()
    assert set(report.stop_s) == {"router", "fleet 1"}

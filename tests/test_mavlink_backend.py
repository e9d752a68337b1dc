"""The MAVLink backend against the MAVLink vehicle simulator: real MAVLink bytes over UDP loopback.

Both sides run at ``SCALE`` times real time (every rate and timeout on both sides is in vehicle /
agent time), so the flights are the real code paths but short.
"""

from __future__ import annotations

import asyncio
import math
import socket
import time
from collections.abc import AsyncIterator, Callable, Iterator
from contextlib import asynccontextmanager, contextmanager
from pathlib import Path
from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from mavsim.config import VehicleConfig
from mavsim.modes import CopterMode
from mavsim.server import MavsimServer
from showfile import load_show
from vehicle_agent.backends.base import (
    CommandRefusedError,
    NotReadyError,
    Setpoint,
    VehicleBackend,
    VehicleSnapshot,
)
from vehicle_agent.backends.mavlink.backend import MavlinkBackend
from vehicle_agent.backends.mavlink.errors import (
    ArmingRefusedError,
    EstimateOffMocapError,
    LinkLostError,
    PrearmFailingError,
    VehicleFaultError,
)
from vehicle_agent.backends.mavlink.mocap import PX4_ORIGIN_AFTER_POSES_S, MocapPose
from vehicle_agent.backends.mavlink.settings import MavlinkSettings, settings_from_show
from vehicle_agent.backends.mavlink.state import ARDUPILOT, PX4, PX4_OFFBOARD_ON_GROUND
from vehicle_agent.motion import plan_move

pytestmark = pytest.mark.timeout(60)

SCALE = 2.0
EPOCH_S = 1000.0
"""The agent clock does not start at 0 (the backend must not assume it does)."""
HOME = (1.0, -1.2, 0.0)
HOVER = (1.0, -1.2, 0.6)

SHOWS = Path(__file__).resolve().parents[1] / "shows"


@contextmanager
def vehicle(**overrides: Any) -> Iterator[MavsimServer]:
    settings: dict[str, Any] = {"position_source_delay_s": 0.0, **overrides}
    config = VehicleConfig(vehicle_id="uav3", system_id=7, port=0, home_m_enu=HOME, **settings)
    server = MavsimServer([config], time_scale=SCALE).start()
    try:
        yield server
    finally:
        server.stop()


class Driver:
    """The agent's fixed-rate loop, reduced to what the backend sees: paced against the wall
    clock (x ``SCALE``) and, as the agent does for a real vehicle (``TickClock``'s
    ``skip_when_late``), jumping ahead after a stall, e.g. an awaited take-off, rather than
    running the missed ticks back to back (agent time seconds ahead of the autopilot's
    heartbeats: a lost link that is the harness's own, seen on a loaded machine)."""

    def __init__(self, backend: MavlinkBackend) -> None:
        self.backend = backend
        self.dt = backend.control_period_s
        self.k = 0
        self.t0 = time.monotonic()
        self.ticked_s = self.now
        """Agent time of the last tick as the backend saw it (after any skip ahead)."""

    @property
    def now(self) -> float:
        return EPOCH_S + self.k * self.dt

    async def tick(self, setpoint: Setpoint | None = None) -> VehicleSnapshot:
        due = math.floor((time.monotonic() - self.t0) * SCALE / self.dt)
        self.k = max(self.k, due - 1)  # late by more than a tick: skip to now
        self.ticked_s = self.now
        snapshot = await self.backend.tick(setpoint, self.ticked_s)
        self.k += 1
        await asyncio.sleep(max(0.0, self.t0 + self.k * self.dt / SCALE - time.monotonic()))
        return snapshot

    async def until(
        self,
        done: Callable[[VehicleSnapshot], bool],
        within_s: float,
        setpoint: Callable[[float], Setpoint | None] = lambda _t: None,
    ) -> VehicleSnapshot:
        end = self.now + within_s
        while self.now < end:
            snapshot = await self.tick(setpoint(self.now))
            if done(snapshot):
                return snapshot
        raise AssertionError(f"not done within {within_s} s of agent time: {snapshot}")

    def pause(self, agent_s: float) -> None:
        """The agent's loop stalls (no tick) for ``agent_s``; its clock jumps ahead."""
        time.sleep(agent_s / SCALE)
        skipped = round(agent_s / self.dt)
        self.k += skipped
        self.t0 = time.monotonic() - self.k * self.dt / SCALE


def assert_streamed_at(
    sends: list[tuple[float, int]], last_sent_s: float, rate_hz: float, tick_s: float
) -> None:
    """The stream sent one setpoint at the first tick 1 / ``rate_hz`` (less half a tick) after
    the previous one (``last_sent_s`` before the first tick), none between: 50 Hz on the 100 Hz
    control loop, every other tick. Counted in ticks of agent time, not per wall second: the
    agent skips ticks on a loaded machine."""
    assert tick_s < 1.0 / rate_hz
    for now_s, sent in sends:
        due = now_s - last_sent_s >= 1.0 / rate_hz - tick_s / 2
        assert sent == int(due), f"{sent} setpoints at {now_s:.3f} s, last at {last_sent_s:.3f}"
        last_sent_s = now_s if due else last_sent_s
    assert {sent for _, sent in sends} == {0, 1}  # ticks with and without a setpoint were seen


@asynccontextmanager
async def connected(
    server: MavsimServer, **settings: Any
) -> AsyncIterator[tuple[MavlinkBackend, Driver]]:
    backend = MavlinkBackend(
        MavlinkSettings(url=server.endpoints[0].url, origin_m_enu=HOME, **settings)
    )
    assert isinstance(backend, VehicleBackend)
    await backend.start()
    try:
        yield backend, Driver(backend)
    finally:
        await backend.close()


async def airborne(backend: MavlinkBackend, driver: Driver) -> VehicleSnapshot:
    await backend.takeoff(HOVER)
    return await driver.until(lambda s: s.mode == "hold", 6.0)


@pytest.mark.parametrize(
    ("overrides", "reason"),
    [
        ({"position_source_delay_s": 60.0}, "PreArm: Need Position Estimate"),
        ({"arm_refusal": "Compass not calibrated"}, "PreArm: Compass not calibrated"),
        (
            {"arm_refusal": "horizontal velocity unstable", "autopilot": "px4"},
            "Preflight Fail: horizontal velocity unstable",
        ),
    ],
)
def test_failing_pre_arm_checks_are_explained_and_no_arming_is_tried(
    overrides: dict[str, Any], reason: str
) -> None:
    # failing since boot: the autopilot said why before we listened, so the backend asks it
    # (MAV_CMD_RUN_PREARM_CHECKS, as a ground station's "check"); a take-off is refused in the
    # autopilot's words without a mode change or an ARM sent
    async def scenario(server: MavsimServer) -> None:
        ap = server.endpoints[0].autopilot
        async with connected(server) as (backend, driver):
            await driver.until(lambda s: s.preflight == reason, 4.0)
            with pytest.raises(PrearmFailingError) as refused:
                await backend.takeoff(HOVER)
            assert refused.value.reason == reason
            assert reason in str(refused.value) and "not arming" in str(refused.value)
            assert isinstance(refused.value, CommandRefusedError)  # the agent will try again
            answered = {command for command, _result in backend.state.acks}
            assert answered.isdisjoint({176, 400})  # neither DO_SET_MODE nor ARM was sent
            assert (ap.mode, ap.armed, ap.setpoints_received) == (CopterMode.STABILIZE, False, 0)
            snapshot = await driver.tick()
            assert (snapshot.mode, snapshot.armed, snapshot.fault) == ("idle", False, None)
            assert snapshot.preflight == reason

    with vehicle(**overrides) as server:
        asyncio.run(scenario(server))


@pytest.mark.parametrize(
    ("autopilot", "said"),
    [("ardupilot", "PreArm: "), ("px4", "Preflight Fail: ")],
)
def test_a_vehicle_waits_out_its_pre_arm_checks_then_takes_off(autopilot: str, said: str) -> None:
    # as PX4 SITL before most take-offs: the estimator unsettled for a while, said as it begins
    async def scenario(server: MavsimServer) -> None:
        ap = server.endpoints[0].autopilot
        async with connected(server) as (backend, driver):
            await driver.until(lambda s: backend.state.prearm_good is True, 4.0)
            assert (await driver.tick()).preflight is None
            ap.prearm_fault = "horizontal velocity unstable"
            waiting = await driver.until(lambda s: s.preflight is not None, 4.0)
            assert waiting.preflight == f"{said}horizontal velocity unstable"
            assert 401 not in {command for command, _ in backend.state.acks}  # no need to ask
            with pytest.raises(PrearmFailingError):
                await backend.takeoff(HOVER)
            assert not ap.armed and 400 not in {command for command, _ in backend.state.acks}
            ap.prearm_fault = None
            await driver.until(lambda s: s.preflight is None, 4.0)
            await airborne(backend, driver)
            assert ap.armed

    with vehicle(autopilot=autopilot) as server:
        asyncio.run(scenario(server))


def test_px4_found_in_offboard_on_the_ground_is_put_in_hold_and_then_judged() -> None:
    """A PX4 left disarmed in OFFBOARD (an earlier agent, a refused arming) shows its pre-arm
    bit clear whatever its checks say: not ready, said so, until the agent has it in Hold."""

    async def scenario(server: MavsimServer) -> None:
        ap = server.endpoints[0].autopilot
        ap.mode = ap.chosen_mode = CopterMode.GUIDED  # OFFBOARD, with no stream
        async with connected(server) as (backend, driver):
            first = await driver.until(lambda s: s.autopilot_mode is not None, 2.0)
            assert first.autopilot_mode == "OFFBOARD"
            assert first.preflight == PX4_OFFBOARD_ON_GROUND and first.mode == "idle"
            ready = await driver.until(lambda s: s.preflight is None, 4.0)
            assert ready.autopilot_mode == "AUTO.LOITER" and ap.mode == CopterMode.LOITER
            await airborne(backend, driver)
            assert ap.armed and ap.mode == CopterMode.GUIDED

    with vehicle(autopilot="px4", guided_timeout_s=1.0) as server:
        asyncio.run(scenario(server))


def test_take_off_follow_a_move_and_land_over_udp() -> None:
    async def scenario(server: MavsimServer) -> None:
        ap = server.endpoints[0].autopilot
        async with connected(server, telemetry_rate_hz=100.0) as (backend, driver):
            assert backend.state.system_id == 7 and backend.state.flavor is ARDUPILOT
            await driver.until(lambda _s: backend.state.prearm_good is True, 2.0)  # SYS_STATUS
            hold = await airborne(backend, driver)
            # telemetry asked with MAV_CMD_SET_MESSAGE_INTERVAL (LOCAL_POSITION_NED, SYS_STATUS)
            intervals = server.endpoints[0].intervals_s
            assert (intervals[32], intervals[1]) == (pytest.approx(0.01), pytest.approx(1.0))
            assert hold.position_m_enu[2] == pytest.approx(HOVER[2], abs=0.1)
            await driver.until(lambda s: math.dist(s.position_m_enu, HOVER) < 0.01, 8.0)
            move = plan_move(HOVER, (1.4, -0.9, 0.7), driver.now, v_max_mps=0.6, a_max_mps2=0.8)
            sends: list[tuple[float, int]] = []  # (agent time of the tick, setpoints it sent)
            last_sent_s = backend.stream.last_sent_s
            worst = 0.0
            while not move.done(driver.now):
                sent_before = backend.setpoints_sent
                snapshot = await driver.tick(move.setpoint(driver.now))
                # the time the backend saw: a tick late on a loaded machine skips ahead (a tick
                # counted at the time before its skip once looked like a setpoint missed, CI)
                sends.append((driver.ticked_s, backend.setpoints_sent - sent_before))
                assert snapshot.mode == "offboard"
                # the snapshot is the state at the end of the tick, the reference is of its start
                reference = move.setpoint(driver.now - driver.dt).position_m_enu
                worst = max(worst, math.dist(snapshot.position_m_enu, reference))
            assert_streamed_at(sends, last_sent_s, rate_hz=50.0, tick_s=driver.dt)
            assert worst < 0.06  # ArduCopter's shaped path trails by 0.05-0.1 s (lead aside)
            settled = await driver.until(lambda s: s.mode == "hold", 1.0)
            assert math.dist(settled.position_m_enu, move.end_m_enu) < 0.03
            assert ap.setpoints_received >= backend.setpoints_sent - 5
            await backend.land()
            landed = await driver.until(lambda s: s.mode == "idle", 6.0)
            assert landed.on_ground and not landed.armed and landed.fault is None
            assert landed.position_m_enu[2] == pytest.approx(HOME[2], abs=1e-6)
            assert landed.battery_fraction is not None and 0.9 < landed.battery_fraction <= 1.0
            assert [t for _, t in backend.events] == ["Arming motors", "Disarming motors"]

    with vehicle() as server:
        asyncio.run(scenario(server))


def test_a_stopped_setpoint_stream_triggers_the_vehicles_failsafe_and_is_reported() -> None:
    async def scenario(server: MavsimServer) -> None:
        ap = server.endpoints[0].autopilot
        async with connected(server, setpoint_timeout_s=1.0) as (backend, driver):
            await airborne(backend, driver)
            move = plan_move(HOVER, (1.6, -1.2, 0.6), driver.now, v_max_mps=0.6, a_max_mps2=0.8)
            for _ in range(50):
                await driver.tick(move.setpoint(driver.now))
            driver.pause(1.6)  # the agent stalls: no setpoint for longer than GUID_TIMEOUT
            assert ap.target.velocity_mps_enu == (0.0, 0.0, 0.0)  # the vehicle stops the move
            snapshot = await driver.tick(move.setpoint(driver.now))
            assert snapshot.fault is not None and "setpoint stream stopped" in snapshot.fault
            sent, received = backend.setpoints_sent, ap.setpoints_received
            for _ in range(500):  # the vehicle brakes to a stop on its own (ArduCopter: a shaped
                # stop, then its P-PI settles: seconds); we stream nothing
                snapshot = await driver.tick(move.setpoint(driver.now))
            for _ in range(50):
                later = await driver.tick(move.setpoint(driver.now))
            assert math.dist(later.position_m_enu, snapshot.position_m_enu) < 0.005
            assert math.hypot(*later.velocity_mps_enu) < 0.01
            assert (backend.setpoints_sent, ap.setpoints_received) == (sent, received)
            assert later.fault == snapshot.fault and later.mode == "hold"
            assert ap.guided_timeout_s == 1.0  # the agent set GUID_TIMEOUT at connect

    with vehicle(guided_timeout_s=3.0) as server:
        asyncio.run(scenario(server))


@pytest.mark.slow
def test_px4_offboard_take_off_fly_land_and_offboard_loss() -> None:
    """PX4: stream first, OFFBOARD, arm, climb on our own setpoints, AUTO.LAND; then a stream
    stopped in flight makes the vehicle leave OFFBOARD on its own, which is reported."""

    async def scenario(server: MavsimServer) -> None:
        ap = server.endpoints[0].autopilot
        async with connected(server) as (backend, driver):
            assert backend.state.flavor is PX4
            await airborne(backend, driver)
            assert ap.mode == CopterMode.GUIDED and ap.armed  # GUIDED is OFFBOARD inside mavsim
            goal = (1.3, -1.0, 0.6)
            move = plan_move(HOVER, goal, driver.now, v_max_mps=0.6, a_max_mps2=0.8)
            await driver.until(lambda s: move.done(driver.now), 4.0, move.setpoint)
            # PX4's MPC loop trails the move: land once there (its default gains, 1-3 s)
            await driver.until(lambda s: math.dist(s.position_m_enu, goal) < 0.02, 4.0,
                               lambda _t: Setpoint(goal))  # fmt: skip
            await backend.land()
            seen: list[VehicleSnapshot] = []
            landed = await driver.until(lambda s: seen.append(s) or s.mode == "idle", 9.0)
            assert math.dist(landed.position_m_enu[:2], goal[:2]) < 0.03 and not landed.armed
            # PX4 shows OFFBOARD again once disarmed; the landing ends when the agent has it in
            # Hold, where its pre-arm bit says what its checks say (in OFFBOARD it stays clear:
            # no stream), and no pre-arm state is told before
            assert landed.autopilot_mode == "AUTO.LOITER" and landed.preflight is None
            assert "OFFBOARD" in {s.autopilot_mode for s in seen if not s.armed}
            assert all(s.preflight is None for s in seen)
            await airborne(backend, driver)
            driver.pause(1.5)
            snapshot = await driver.tick(Setpoint(HOVER))
            assert snapshot.fault is not None and "setpoint stream stopped" in snapshot.fault
            # PX4 v1.16: COM_OBL_RC_ACT 0 flies Position mode, shown as POSCTL
            await driver.until(lambda s: s.autopilot_mode == "POSCTL", 1.0)

            def failsafe_said(_s: VehicleSnapshot) -> bool:
                return any(text == "Failsafe activated: switching to Position"
                           for _, text in backend.events)  # fmt: skip

            await driver.until(failsafe_said, 2.0)  # PX4 sends texts to us: we are a GCS
            assert [text for _, text in backend.events].count("Arming motors") == 2

    with vehicle(autopilot="px4", guided_timeout_s=1.0) as server:
        asyncio.run(scenario(server))


def pilot_switch(port: int, system_id: int, mode: CopterMode) -> None:
    """A pilot's ground station (system 250) switches the vehicle's mode."""
    pilot = mavlink.MAVLink(None, srcSystem=250, srcComponent=190)
    command = pilot.command_long_encode(system_id, 1, mavlink.MAV_CMD_DO_SET_MODE, 0,
                                        1, int(mode), 0, 0, 0, 0, 0)  # fmt: skip
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.sendto(command.pack(pilot), ("127.0.0.1", port))


def test_a_pilot_mode_change_stops_the_stream_and_is_never_fought() -> None:
    async def scenario(server: MavsimServer) -> None:
        ap = server.endpoints[0].autopilot
        async with connected(server) as (backend, driver):
            await airborne(backend, driver)
            for _ in range(20):
                await driver.tick(Setpoint(HOVER))
            pilot_switch(server.endpoints[0].port, 7, CopterMode.LOITER)
            snapshot = await driver.until(lambda s: s.fault is not None, 3.0,
                                          lambda _t: Setpoint(HOVER))  # fmt: skip
            assert "LOITER" in str(snapshot.fault) and "pilot" in str(snapshot.fault)
            sent = backend.setpoints_sent
            for _ in range(50):
                await driver.tick(Setpoint(HOVER))
            assert backend.setpoints_sent == sent
            with pytest.raises(VehicleFaultError):
                await backend.land()
            assert ap.mode == CopterMode.LOITER and ap.armed

    with vehicle() as server:
        asyncio.run(scenario(server))


def test_a_silent_vehicle_is_a_lost_link() -> None:
    async def scenario(server: MavsimServer) -> None:
        async with connected(server, heartbeat_timeout_s=1.5) as (_, driver):
            await driver.until(lambda s: s.position_m_enu == pytest.approx(HOME), 1.0)
            server.stop()
            snapshot = await driver.until(lambda s: s.fault is not None, 3.0)
            assert "no heartbeat" in str(snapshot.fault)

    with vehicle() as server:
        asyncio.run(scenario(server))


def test_a_stalled_agent_is_not_a_lost_link() -> None:
    """The agent's clock jumps after a stall (skip_when_late); heartbeats wait in the socket."""

    async def scenario(server: MavsimServer) -> None:
        async with connected(server, heartbeat_timeout_s=1.5) as (_, driver):
            await driver.tick()
            driver.pause(4.0)
            for _ in range(100):
                snapshot = await driver.tick()
                assert snapshot.fault is None

    with vehicle() as server:
        asyncio.run(scenario(server))


def test_no_vehicle_at_the_url_is_an_error_at_start(free_tcp_port: Callable[[], int]) -> None:
    async def scenario() -> None:
        url = f"udp:127.0.0.1:{free_tcp_port()}"
        backend = MavlinkBackend(MavlinkSettings(url=url, origin_m_enu=HOME, connect_timeout_s=0.6))
        with pytest.raises(LinkLostError, match="no autopilot heartbeat"):
            await backend.start()

    asyncio.run(scenario())


def test_mocap_flows_at_its_rate_while_the_control_loop_awaits_the_autopilot() -> None:
    # The loop awaits mode changes and arming for seconds; an estimator starved of its position
    # source that long drops it (PX4 SIH: arming refused). Poses keep flowing without ticks.
    asked: list[float] = []

    def source(now_s: float) -> MocapPose:
        asked.append(now_s)
        return MocapPose(position_m_enu=(1.0, -1.0, 0.0))

    async def scenario(server: MavsimServer) -> None:
        # forwarding alone here (the next test: fusion and arming)
        async with connected(server, mocap="vision_position_estimate", mocap_rate_hz=50.0,
                             set_params=False) as (backend, driver):  # fmt: skip
            backend._mocap.source = source
            for _ in range(50):  # 0.5 s of agent time
                await driver.tick()
            ticking = backend._mocap.sent
            await asyncio.sleep(0.5 / SCALE)  # 0.5 s of agent time without a tick
            stalled = backend._mocap.sent - ticking
            backend._fail("a fault: the autopilot flies on, on the mocap")
            await asyncio.sleep(0.25 / SCALE)
            after_fault = backend._mocap.sent - ticking - stalled
        assert 20 <= ticking <= 27 and 18 <= stalled <= 27, (ticking, stalled)
        assert after_fault >= 8
        assert asked[-1] > driver.now + 0.3  # the agent's clock carried on through the stall
        assert server.endpoints[0].autopilot.mocap_received >= 40

    with vehicle() as server:
        asyncio.run(scenario(server))


MOCAP_AUTOPILOTS = [
    ("ardupilot", (("VISO_TYPE", 1),), "PreArm: VisOdom: not healthy"),
    ("px4", (("EKF2_ASP_DELAY", 0.0), ("EKF2_DELAY_MAX", 20.0)), "Arming denied: Resolve"),
]
VELOCITY_FUSED = {"ardupilot": ("EK3_SRC1_VELXY", 6.0), "px4": ("EKF2_EV_CTRL", 15.0)}
"""The parameter that makes each estimator fuse the velocity ODOMETRY carries, and its value."""


@pytest.mark.parametrize("message", ["vision_position_estimate", "odometry"])
@pytest.mark.parametrize(("autopilot", "boot", "refusal"), MOCAP_AUTOPILOTS)
def test_a_mocap_vehicle_is_set_up_at_connect_and_arms_only_while_poses_flow(
    autopilot: str, boot: tuple[tuple[str, float], ...], refusal: str, message: str
) -> None:
    # The agent's fusion parameters are set and read back as on SITL; with mocap the estimator's
    # only position source, arming waits for poses (a stalled mocap task was refused on PX4 SIH).
    # ODOMETRY counts only in the frames each autopilot takes (mavsim drops the others as they do).
    poses = {"on": False}

    def source(_now_s: float) -> MocapPose | None:
        return MocapPose(position_m_enu=HOME) if poses["on"] else None

    async def scenario(server: MavsimServer) -> None:
        ap = server.endpoints[0].autopilot
        async with connected(server, mocap=message, mocap_rate_hz=50.0) as (backend, driver):
            backend._mocap.source = source
            assert ap.fuses_mocap  # the agent's parameters made mocap the position source
            name, fused = VELOCITY_FUSED[autopilot]
            assert (ap.params[name] == fused) == (message == "odometry")
            for _ in range(30):
                await driver.tick()
            with pytest.raises(ArmingRefusedError) as refused:
                await backend.takeoff(HOVER)
            assert refused.value.reason.startswith(refusal)
            poses["on"] = True
            await driver.until(lambda s: s.preflight is None, 5.0)  # the agent waits so
            for attempt in range(3):  # as the agent retries: a loaded machine may delay a pose
                try:
                    await airborne(backend, driver)
                    break
                except ArmingRefusedError:
                    assert attempt < 2
                    await driver.until(lambda s: s.preflight is None, 5.0)
            assert ap.armed

    with vehicle(autopilot=autopilot, params=boot) as server:
        asyncio.run(scenario(server))


def test_px4_on_mocap_gets_its_ekf_origin_at_altitude_zero_once_poses_flow() -> None:
    # EKF2 (v1.16) takes vision z as down from altitude 0: with its origin anywhere else its
    # local z is off by that altitude (SIH: +584 m on the ground). Given before the first pose
    # (a loaded machine), EKF2 took the barometer's height at the origin and stayed 583.85 m off.
    # ArduPilot gets it when it says it uses external nav (its own GPS origin crashes 4.7 SITL).
    poses = {"on": False}

    def source(_now_s: float) -> MocapPose | None:
        return MocapPose(position_m_enu=HOME) if poses["on"] else None

    async def scenario(server: MavsimServer) -> None:
        ap = server.endpoints[0].autopilot
        settings = {"mocap": "vision_position_estimate", "set_params": False}
        async with connected(server, **settings) as (backend, driver):
            backend._mocap.source = source
            for _ in range(60):  # 0.6 s of agent time, no pose yet
                await driver.tick()
            assert ap.ekf_origin_lla is None
            poses["on"] = True
            await driver.until(lambda _s: backend._mocap.sent > 0, 1.0)
            first_s = driver.now
            await driver.until(lambda _s: ap.ekf_origin_lla is not None, 3.0)
            assert driver.now - first_s >= PX4_ORIGIN_AFTER_POSES_S - 0.1
        assert ap.ekf_origin_lla is not None and ap.ekf_origin_lla[2] == 0.0

    with vehicle(autopilot="px4") as server:
        asyncio.run(scenario(server))


def test_px4_on_mocap_gets_its_home_where_it_stands_and_its_geofence_lets_it_arm() -> None:
    # PX4 SIH takes its home from its GPS at boot, 3.9-4.0 m from where EKF2 puts it once its
    # origin is the show's; GF_MAX_HOR_DIST (from home) then fails its arming checks: a vehicle
    # sat held by its preflight for a whole show (issue 31). The agent puts the home where the
    # vehicle stands (MAV_CMD_DO_SET_HOME, param 1 = 1) once its estimate is on the mocap.
    async def scenario(server: MavsimServer) -> None:
        ap = server.endpoints[0].autopilot
        settings = {"mocap": "vision_position_estimate", "set_params": False}
        async with connected(server, **settings) as (backend, driver):
            backend._mocap.source = lambda _now_s: MocapPose(position_m_enu=HOME)
            said = "Geofence: exceeding maximum distance to Home"
            await driver.until(lambda s: s.preflight == said, 3.0)
            await driver.until(lambda s: s.preflight is None, 6.0)
            assert math.dist(ap.home_m_enu, HOME) < 0.01
            await airborne(backend, driver)

    fence = (("GF_MAX_HOR_DIST", 3.5), ("GF_ACTION", 5.0))
    with vehicle(autopilot="px4", boot_home_offset_m=(2.4, -3.2, 0.0), params=fence) as server:
        asyncio.run(scenario(server))


def test_a_vehicle_whose_estimate_is_not_where_the_mocap_puts_it_is_not_armed() -> None:
    # The autopilot's estimator has not taken the mocap (PX4 SIH: 583.85 m off; 4.46 m in its
    # first seconds): a take-off would climb from the wrong place. Its preflight says so until
    # the estimate comes to the mocap (the agent waits, as for the autopilot's own checks); a
    # take-off asked meanwhile is not ready, with nothing sent and no fault.
    off = {"z_m": 0.5}

    def source(_now_s: float) -> MocapPose:
        return MocapPose(position_m_enu=(HOME[0], HOME[1], HOME[2] + off["z_m"]))

    async def scenario(server: MavsimServer) -> None:
        ap = server.endpoints[0].autopilot
        async with connected(server, mocap="vision_position_estimate", mocap_rate_hz=50.0,
                             set_params=False) as (backend, driver):  # fmt: skip
            backend._mocap.source = source
            await driver.until(lambda _s: backend._mocap.sent > 10, 2.0)
            held = await driver.until(lambda s: s.preflight is not None, 2.0)
            assert held.preflight is not None and "0.50 m from the mocap's" in held.preflight
            with pytest.raises(EstimateOffMocapError, match=r"0\.50 m from the mocap") as refused:
                await backend.takeoff(HOVER)
            assert isinstance(refused.value, NotReadyError)
            assert not ap.armed and backend.mode == "idle" and backend.fault is None
            off["z_m"] = 0.0
            await driver.until(lambda s: s.preflight is None, 2.0)
            await airborne(backend, driver)
            assert ap.armed

    with vehicle() as server:
        asyncio.run(scenario(server))


def test_settings_come_from_the_show_files_typed_vehicle_fields() -> None:
    show = load_show(SHOWS / "rehearsal-mavlink.yaml")
    uav2 = show.vehicle("uav2")
    plain = settings_from_show(show, uav2)
    assert plain.origin_m_enu == uav2.home_m_enu and plain.system_id == 2
    assert (plain.setpoint_rate_hz, plain.mocap) == (50.0, "none")
    tuned = uav2.model_copy(
        update={
            "mavlink_origin_m_enu": (0.5, 0.0, 0.0),
            "mavlink_setpoint_rate_hz": 100.0,
            "mavlink_mocap": "att_pos_mocap",
        }
    )
    settings = settings_from_show(show, tuned)
    assert settings.origin_m_enu == (0.5, 0.0, 0.0)
    assert (settings.setpoint_rate_hz, settings.mocap) == (100.0, "att_pos_mocap")

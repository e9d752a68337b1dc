"""The agent's preflight: the pure checks with known answers and a property, the MAVLink
figures (sequence loss, estimator flags), and a vehicle held by a failing check that the
orchestrator gives no job until it passes."""

from __future__ import annotations

import asyncio
import math
from dataclasses import replace

import pytest
from hypothesis import given
from hypothesis import strategies as st
from test_agent_job_runner import HOME, config
from test_mavlink_backend import HOME as MAV_HOME
from test_mavlink_backend import Driver, connected, vehicle
from test_orchestrator_core import _assigned, _config, _submit

from bus.messages import VehicleCommand
from mavsim.server import MavsimServer
from orchestrator.core import Book
from showfile.geofence import vehicle_fence
from vehicle_agent.backends.base import LinkHealth, VehicleSnapshot
from vehicle_agent.backends.mavlink.health import SequenceLoss, estimator_problem
from vehicle_agent.backends.mavlink.mocap import MocapPose
from vehicle_agent.job_runner import JobRunner
from vehicle_agent.preflight import PreflightLimits, PreflightReadings, preflight_problem

LIMITS = PreflightLimits()
HEALTHY = LinkHealth(link_age_s=0.4, link_loss_fraction=0.0, mocap_age_s=0.02)
GOOD = PreflightReadings(health=HEALTHY, battery_fraction=0.9, clock_offset_s=0.001)


@pytest.mark.parametrize(
    ("changed", "reason"),
    [
        ({}, None),
        (
            {"health": replace(HEALTHY, link_age_s=2.5)},
            "link: no autopilot heartbeat for 2.5 s (limit 2 s)",
        ),
        (
            {"health": replace(HEALTHY, link_loss_fraction=0.12)},
            "link: 12.0% of the autopilot's messages lost (limit 5%)",
        ),
        (  # just over the limit says so (to the percent it read "5% ... (limit 5%)" on SITL)
            {"health": replace(HEALTHY, link_loss_fraction=0.052)},
            "link: 5.2% of the autopilot's messages lost (limit 5%)",
        ),
        (
            {"health": replace(HEALTHY, estimator="no horizontal position")},
            "estimator: no horizontal position",
        ),
        (
            {"health": replace(HEALTHY, mocap_age_s=0.35)},
            "mocap: last pose sent 350 ms ago (limit 200 ms)",
        ),
        (
            {"health": replace(HEALTHY, mocap_age_s=math.inf)},
            "mocap: no pose sent to the autopilot yet",
        ),
        (  # the cause before its effect, whichever the autopilot said first
            {"health": replace(HEALTHY, mocap_age_s=math.inf, estimator="no horizontal position")},
            "mocap: no pose sent to the autopilot yet",
        ),
        ({"has_fence": False}, "geofence: none loaded"),
        (
            {
                "health": replace(
                    HEALTHY, fence="the autopilot's fence (GF_ACTION) was not read back"
                )
            },
            "geofence: the autopilot's fence (GF_ACTION) was not read back",
        ),
        ({"battery_fraction": 0.2}, "battery: 20% left, at or below the 20% reserve"),
        (
            {"clock_offset_s": -0.08},
            "clock: -80 ms off the orchestrator's (limit 50 ms): synchronise it (NTP/PTP)",
        ),
        ({"autopilot": "PreArm: Compass not calibrated"}, "PreArm: Compass not calibrated"),
        # not measured: not checked (a simulated vehicle, a clock not compared yet)
        ({"health": None, "battery_fraction": None, "clock_offset_s": None}, None),
    ],
)
def test_each_check_says_its_reason_in_an_operators_words(
    changed: dict[str, object], reason: str | None
) -> None:
    assert preflight_problem(replace(GOOD, **changed), LIMITS) == reason  # type: ignore[arg-type]


def test_the_link_is_named_first_when_several_fail() -> None:
    # a stale link makes every other figure stale: it is the one to fix first
    bad = PreflightReadings(
        health=LinkHealth(link_age_s=9.0, mocap_age_s=1.0),
        battery_fraction=0.1,
        autopilot="PreArm: Need Position Estimate",
    )
    assert str(preflight_problem(bad, LIMITS)).startswith("link: no autopilot heartbeat")
    assert str(preflight_problem(replace(bad, health=None), LIMITS)).startswith("battery:")


FIGURES = {
    "link": ("link_age_s", "link_age_max_s"),
    "loss": ("link_loss_fraction", "link_loss_max_fraction"),
    "mocap": ("mocap_age_s", "mocap_age_max_s"),
    "clock": ("clock_offset_s", "clock_offset_max_s"),
}


@given(
    share=st.fixed_dictionaries({name: st.floats(0.0, 1.0) for name in FIGURES}),
    battery=st.floats(0.21, 1.0),
    broken=st.sampled_from([*FIGURES, "battery", None]),
    over=st.floats(1.001, 100.0),
)
def test_readings_within_every_bound_pass_and_one_past_its_bound_fails_by_name(
    share: dict[str, float], battery: float, broken: str | None, over: float
) -> None:
    def figure(name: str) -> float:
        bound = float(getattr(LIMITS, FIGURES[name][1]))
        return bound * (over if name == broken else share[name])

    health = LinkHealth(
        link_age_s=figure("link"), link_loss_fraction=min(1.0, figure("loss")),
        mocap_age_s=figure("mocap"),
    )  # fmt: skip
    readings = PreflightReadings(
        health=health,
        battery_fraction=LIMITS.battery_reserve_fraction / over if broken == "battery" else battery,
        clock_offset_s=-figure("clock"),
    )
    reason = preflight_problem(readings, LIMITS)
    if broken is None:
        assert reason is None
    else:
        word = {"loss": "link", "link": "link"}.get(broken, broken)
        assert reason is not None and reason.startswith(f"{word}:"), reason


def test_sequence_numbers_count_the_messages_lost() -> None:
    clean = SequenceLoss()
    for k in range(600):  # wraps around 255 -> 0 twice: no loss
        clean.saw(1, 1, k % 256)
    assert clean.fraction == 0.0
    lossy = SequenceLoss()
    sent = [k for k in range(1000) if k % 10 != 3]  # one in ten lost
    for k in sent:
        lossy.saw(1, 1, k % 256)
    assert lossy.fraction == pytest.approx(0.1, abs=0.005)
    few = SequenceLoss()
    for k in range(0, 40, 2):
        few.saw(1, 1, k)
    assert few.fraction is None  # too few to say


def test_components_count_apart_and_a_restart_is_no_loss() -> None:
    losses = SequenceLoss()
    for k in range(100):
        losses.saw(1, 1, k)
        losses.saw(1, 191, (k + 77) % 256)  # another component, its own counter
    losses.saw(1, 1, 250)  # the autopilot rebooted: half the range away
    for k in range(251, 300):
        losses.saw(1, 1, k % 256)
    assert losses.fraction == 0.0


@given(st.lists(st.booleans(), min_size=300, max_size=2000))
def test_the_loss_is_the_share_dropped(kept: list[bool]) -> None:
    # runs of drops shorter than half the range: each gap is counted exactly
    kept = [True, *kept]
    for start in range(0, len(kept), 100):
        kept[start] = True
    losses = SequenceLoss(window=10_000)
    for seq, arrived in enumerate(kept):
        if arrived:
            losses.saw(1, 1, seq % 256)
    received = sum(kept) - 1
    dropped = len(kept) - sum(kept) - (len(kept) - 1 - max(i for i, k in enumerate(kept) if k))
    if received < 50:
        assert losses.fraction is None
    else:
        assert losses.fraction == pytest.approx(dropped / (dropped + received))


@pytest.mark.parametrize(
    ("flags", "problem"),
    [
        (None, None),
        (1 | 2 | 4 | 8 | 32 | 16, None),
        (1 | 2 | 4 | 32, "no horizontal position"),
        (1 | 4 | 32, "no horizontal velocity, no horizontal position"),
        (1 | 2 | 4 | 8 | 32 | 128, None),  # PX4 at rest on mocap (vehicle_at_rest), measured
        (1 | 2 | 4 | 32 | 128, "no horizontal position"),
    ],
)
def test_estimator_flags_in_words(flags: int | None, problem: str | None) -> None:
    assert estimator_problem(flags) == problem


def _on_ground(health: LinkHealth) -> VehicleSnapshot:
    return VehicleSnapshot(
        t_s=0.0, position_m_enu=HOME, velocity_mps_enu=(0.0, 0.0, 0.0), armed=False,
        mode="idle", on_ground=True, battery_fraction=0.9, health=health,
    )  # fmt: skip


def test_a_vehicle_held_by_its_preflight_gets_no_job_until_it_passes() -> None:
    fence = vehicle_fence([(-1.0, 0.0), (1.0, 1.0)], HOME, 0.5, margin_m=0.5, ceiling_margin_m=0.5)
    cfg = config()
    runner = JobRunner(replace(cfg, preflight=LIMITS, safety=replace(cfg.safety, fence=fence)))
    book = Book(_config(), now_s=0.0)
    book.liveliness("uav1", True, 0.0)
    stale = _on_ground(replace(HEALTHY, mocap_age_s=0.5))
    runner.step(stale, 0.0)
    assert runner.preflight == "mocap: last pose sent 500 ms ago (limit 200 ms)"
    assert not _assigned(book.status(runner.status(), 0.1))
    assert not _assigned(_submit(book, "j1", 0.2))
    for k in range(1, 40):  # held while it lasts, and a tick changes nothing
        runner.step(stale, 0.1 * k)
        assert not _assigned(book.status(runner.status(), 0.1 * k)) and not _assigned(
            book.tick(0.1 * k)
        )
    (summary,) = [v for v in book.snapshot(4.0).vehicles if v.vehicle_id == "uav1"]
    assert summary.preflight == runner.preflight and "mocap" in summary.message
    runner.step(_on_ground(HEALTHY), 4.0)
    assert runner.preflight is None
    eff = book.status(runner.status(), 4.1)
    assert _assigned(eff) == [("uav1", "j1")]
    ((_, command),) = [(v, c) for v, c in eff.commands if c.command == "assign"]
    assert isinstance(command, VehicleCommand) and runner.handle_command(command, 4.2).ok
    assert runner.state == "taking_off"


def test_on_mavsim_missing_mocap_then_a_silent_autopilot_hold_the_vehicle() -> None:
    # real MAVLink bytes: the figures come from the backend's link, the runner decides
    poses = {"on": False}
    cfg = config()
    fence = vehicle_fence(
        [(0.0, -1.0), (2.0, 0.0)], MAV_HOME, 0.5, margin_m=0.5, ceiling_margin_m=0.5
    )
    runner = JobRunner(replace(cfg, preflight=LIMITS, safety=replace(cfg.safety, fence=fence)))

    def source(_now_s: float) -> MocapPose | None:
        return MocapPose(position_m_enu=MAV_HOME) if poses["on"] else None

    async def step(driver: Driver) -> VehicleSnapshot:
        snapshot = await driver.tick()
        runner.step(snapshot, driver.now)
        return snapshot

    async def scenario(server: MavsimServer) -> None:
        async with connected(server, mocap="vision_position_estimate") as (backend, driver):
            backend._mocap.source = source
            for _ in range(50):
                await step(driver)
            assert runner.preflight == "mocap: no pose sent to the autopilot yet"
            poses["on"] = True
            for _ in range(500):
                snapshot = await step(driver)
                if runner.preflight is None:
                    break
            assert runner.preflight is None, runner.preflight
            assert snapshot.health is not None and snapshot.health.link_loss_fraction == 0.0
            poses["on"] = False
            for _ in range(40):  # 0.4 s without a pose
                await step(driver)
            assert str(runner.preflight).startswith("mocap: last pose sent ")
            poses["on"] = True
            for _ in range(20):
                await step(driver)
            server.stop()  # the autopilot falls silent
            held = []
            for _ in range(400):
                snapshot = await step(driver)
                held.append(runner.preflight)
                if snapshot.fault is not None:
                    break
            said = [p for p in held if p is not None]
            assert said and said[0].startswith("link: no autopilot heartbeat for 2.")
            assert snapshot.fault is not None and "no heartbeat" in snapshot.fault

    boot = (("EKF2_ASP_DELAY", 0.0), ("EKF2_DELAY_MAX", 20.0))  # set for mocap before boot
    with vehicle(autopilot="px4", params=boot) as server:
        asyncio.run(scenario(server))

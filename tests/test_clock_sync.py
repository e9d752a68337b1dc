"""The agent's clock against the orchestrator's (issue 32, preflight and health), without a bus:
the NTP on-wire arithmetic, its filter, the preflight that holds the vehicle and the orchestrator's
one alert. Over a real secured bus: ``tests/test_clock_offset_live.py``."""

from __future__ import annotations

from dataclasses import replace

import msgspec
import pytest
from hypothesis import given
from hypothesis import strategies as st
from test_agent_job_runner import HOME, config
from test_agent_preflight import HEALTHY, LIMITS
from test_orchestrator_core import _assigned, _config, _submit

from bus.messages import Event
from orchestrator.clock_offsets import clock_reply
from orchestrator.core import Book
from vehicle_agent.backends.base import LinkHealth, VehicleSnapshot
from vehicle_agent.clock_sync import ClockFilter, ClockSample, on_wire
from vehicle_agent.job_runner import JobRunner
from vehicle_agent.safety import vehicle_fence


def _exchange(
    offset_s: float, there_s: float, back_s: float, busy_s: float = 0.0, start_s: float = 1e9
) -> tuple[float, float, float, float]:
    """t1..t4 of an exchange begun at true time ``start_s``: the agent's clock ``offset_s``
    ahead of the orchestrator's (which tells true time), ``there_s`` and ``back_s`` on the
    wire, ``busy_s`` in the orchestrator."""
    t2 = start_s + there_s
    t3 = t2 + busy_s
    return start_s + offset_s, t2, t3, t3 + back_s + offset_s


def test_a_symmetric_exchange_gives_the_offset_exactly_and_the_round_trip() -> None:
    sample = on_wire(100.0, 99.8015, 99.8025, 100.004)  # 1.5 ms each way, 1 ms inside
    assert sample.offset_s == pytest.approx(0.2, abs=1e-9)  # the agent is 200 ms ahead
    assert sample.delay_s == pytest.approx(0.003, abs=1e-9)  # its own 1 ms taken out
    behind = on_wire(*_exchange(-0.35, 0.002, 0.002, busy_s=0.5))
    assert behind.offset_s == pytest.approx(-0.35, abs=1e-6)  # Unix times: float64 to 0.24 us
    assert behind.delay_s == pytest.approx(0.004, abs=1e-6)


def test_a_one_way_delay_is_what_the_estimate_cannot_see_half_the_round_trip() -> None:
    sample = on_wire(100.0, 99.803, 99.803, 100.003)  # 3 ms there, nothing back
    assert sample.offset_s == pytest.approx(0.1985, abs=1e-9)
    assert sample.delay_s == pytest.approx(0.003, abs=1e-9)
    back = on_wire(*_exchange(0.2, 0.0, 0.003))  # all of it on the way back: the other side
    assert back.offset_s == pytest.approx(0.2015, abs=1e-6)


times = st.floats(min_value=0.0, max_value=2.0)


@given(
    offset_s=st.floats(min_value=-30.0, max_value=30.0),
    there_s=times,
    back_s=times,
    busy_s=st.floats(min_value=0.0, max_value=0.5),
    start_s=st.floats(min_value=1.6e9, max_value=2.0e9),
)
def test_the_estimate_is_within_half_the_delay_of_the_true_offset_for_any_split(
    offset_s: float, there_s: float, back_s: float, busy_s: float, start_s: float
) -> None:
    sample = on_wire(*_exchange(offset_s, there_s, back_s, busy_s, start_s))
    ulp_s = 2e-6  # a few ulps of a Unix time in float64 (2.4e-7 s each)
    assert sample.delay_s == pytest.approx(there_s + back_s, abs=ulp_s)
    assert abs(sample.offset_s - offset_s) <= sample.delay_s / 2 + ulp_s
    assert sample.offset_s - offset_s == pytest.approx((back_s - there_s) / 2, abs=ulp_s)


def test_the_filter_trusts_the_least_delayed_of_its_latest_samples() -> None:
    kept = ClockFilter(size=4)
    assert kept.best is None
    quick = ClockSample(offset_s=0.201, delay_s=0.001)
    slow = ClockSample(offset_s=0.150, delay_s=0.100)  # waited in a queue on its way back
    assert kept.add(slow) == slow
    assert kept.add(quick) == quick
    for _ in range(3):
        assert kept.add(slow) == quick  # outvoted while it is among the latest four
    assert kept.add(slow) == slow  # and forgotten after: a clock put right is seen in time
    assert kept.add(ClockSample(offset_s=9.0, delay_s=-0.5)) == slow  # a clock set mid-way


def test_the_orchestrator_replies_with_its_receive_then_transmit_time() -> None:
    stamps = iter([1000.25, 1000.5])
    reply = clock_reply(lambda: next(stamps))
    assert (reply.receive_s, reply.transmit_s) == (1000.25, 1000.5)


def _on_ground(health: LinkHealth = HEALTHY) -> VehicleSnapshot:
    return VehicleSnapshot(
        t_s=0.0, position_m_enu=HOME, velocity_mps_enu=(0.0, 0.0, 0.0), armed=False,
        mode="idle", on_ground=True, battery_fraction=0.9, health=health,
    )  # fmt: skip


def _clock_events(events: list[Event]) -> list[tuple[str, str]]:
    return [(e.level, e.message) for e in events if e.kind == "clock_offset"]


def test_a_vehicle_whose_clock_is_off_is_held_and_the_orchestrator_alerts_once() -> None:
    fence = vehicle_fence([(-1.0, 0.0), (1.0, 1.0)], HOME, 0.5, margin_m=0.5, ceiling_margin_m=0.5)
    cfg = config()
    runner = JobRunner(replace(cfg, preflight=LIMITS, safety=replace(cfg.safety, fence=fence)))
    book = Book(_config(clock_offset_max_s=LIMITS.clock_offset_max_s), now_s=0.0)
    book.liveliness("uav1", True, 0.0)
    runner.step(_on_ground(), 0.0)
    assert runner.preflight is None and runner.status().clock_offset_ms is None  # not measured
    runner.clock_offset_s = 0.2004
    runner.step(_on_ground(), 0.1)
    assert runner.preflight == (
        "clock: +200 ms off the orchestrator's (limit 50 ms): synchronise it (NTP/PTP)"
    )
    assert runner.status().clock_offset_ms == 200
    events: list[Event] = []
    for k in range(1, 30):  # statuses keep coming: one alert, and no job meanwhile
        eff = book.status(runner.status(), 0.1 * k)
        events += eff.events
        assert not _assigned(eff)
        if k == 2:
            assert not _assigned(_submit(book, "j1", 0.25))
    assert _clock_events(events) == [
        (
            "alert",
            "uav1 clock +200 ms off the orchestrator's (limit 50 ms): held by its preflight; "
            "synchronise its clock (NTP/PTP)",
        )
    ]
    assert [e.kind for e in book.open_alerts()] == ["clock_offset"]
    restarted = msgspec.structs.replace(runner.status(), clock_offset_ms=None)  # not measured
    assert not _clock_events(book.status(restarted, 3.0).events)
    assert [e.kind for e in book.open_alerts()] == ["clock_offset"]
    runner.clock_offset_s = -0.003  # its clock put right
    runner.step(_on_ground(), 3.1)
    assert runner.preflight is None
    eff = book.status(runner.status(), 3.2)
    assert _clock_events(eff.events) == [
        ("info", "uav1 clock within 50 ms of the orchestrator's (-3 ms)")
    ]
    assert book.open_alerts() == [] and _assigned(eff) == [("uav1", "j1")]

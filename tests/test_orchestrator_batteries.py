"""Batteries in dispatch (``orchestrator/batteries.py``, ``orchestrator/battery_swaps.py``): no
job a vehicle cannot write, return and land from with the show's reserve; the swap, its
confirmation by the crew, the fresh pack's report; the ETAs count swaps."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bus.messages import OperatorCommand, SubmitRequest, VehicleStatus
from orchestrator.batteries import JobLeg, Swaps, charge_after, job_energy_wh, shortfall
from orchestrator.core import Book, CoreConfig, Effects
from orchestrator.fleet import EtaModel, VehicleInfo
from showfile import ShowError, parse_show
from sim.battery import BatteryState, discharge
from vehicles.batteries import kind_battery

QUAD = kind_battery("quadrotor-brush")
VEHICLES = (VehicleInfo("uav1", "quadrotor-brush", "b1"),)


def _book(reserve: float = 0.2, *, swap_s: float = 60.0) -> Book:
    config = CoreConfig(
        show_id="t",
        vehicles=VEHICLES,
        eta=EtaModel(time_scale=1.0),
        batteries=(("quadrotor-brush", QUAD),),
        battery_reserve_fraction=reserve,
        battery_swap_s=swap_s,
    )
    book = Book(config, now_s=0.0)
    book.liveliness("uav1", True, 0.0)
    return book


def _status(book: Book, charge: float | None, now_s: float, state: str = "idle") -> Effects:
    status = VehicleStatus(vehicle_id="uav1", kind="quadrotor-brush", state=state,  # type: ignore[arg-type]
                           battery_fraction=charge, battery_minutes_left=None)  # fmt: skip
    return book.status(status, now_s)


def _submit(book: Book, job_id: str, now_s: float, estimate_s: float = 10.0) -> Effects:
    request = SubmitRequest(text="L")
    reply, eff = book.submit(job_id, request, label="L", estimate_s=estimate_s, now_s=now_s)
    assert reply.ok
    return eff


def _assigned(eff: Effects) -> list[tuple[str, str]]:
    return [(vid, c.job.job_id) for vid, c in eff.commands if c.command == "assign" and c.job]


def test_a_jobs_charge_agrees_with_flying_it_on_the_pack_model() -> None:
    # 30 s at 105.1 W (approach 11 s, writing 10 s, back 9 s: every phase at hover power)
    leg = JobLeg(approach_s=11.0, writing_s=10.0, back_s=9.0)
    assert job_energy_wh(QUAD, leg) == pytest.approx(QUAD.power_w.hover_w * 30.0 / 3600.0)
    for start in (1.0, 0.6, 0.3):
        state = BatteryState(charge_fraction=start)
        for _ in range(3000):
            state = discharge(QUAD.pack, state, QUAD.power_w.hover_w, 0.01)
        predicted = charge_after(QUAD, start, job_energy_wh(QUAD, leg))
        assert start - predicted == pytest.approx(start - state.charge_fraction, rel=5e-3)


def test_a_vehicle_short_of_its_reserve_is_sent_for_a_swap_and_flies_after_it() -> None:
    book = _book()
    _status(book, 0.21, 1.0)  # 10 s of writing would leave 19 %
    eff = _submit(book, "j1", 2.0)
    assert _assigned(eff) == []
    (swap,) = [e for e in eff.events if e.kind == "battery_swap"]
    assert "21% left" in swap.message and "reserve 20%" in swap.message
    (summary,) = book.snapshot(2.0).vehicles
    assert summary.state == "battery_swap" and summary.message.startswith("battery swap: ")
    command = OperatorCommand(command="battery_swapped", vehicle_id="uav1", operator="crew-ana")
    reply, eff = book.operator(command, 32.0)
    assert reply.ok and [c.command for _, c in eff.commands] == ["battery_swapped"]
    assert any(e.kind == "operator" and "crew-ana: battery_swapped uav1" in e.message
               for e in eff.events)  # fmt: skip
    assert book.swaps.turnaround_s == pytest.approx(30.0)  # the crew's own pace, not 60 s
    assert _assigned(_status(book, 0.21, 33.0)) == []  # the old pack's figure: not yet
    assert book.snapshot(33.0).vehicles[0].state == "battery_swap"
    assert _assigned(_status(book, 1.0, 34.0)) == [("uav1", "j1")]


def test_a_fresh_pack_that_reported_before_the_crew_confirmed_ends_the_swap() -> None:
    # an autopilot restarted by the swap, or PX4 SITL (full again once disarmed), reports the
    # fresh pack while the vehicle still waits for the crew: the charge it was sent with counts
    book = _book()
    _status(book, 0.21, 1.0)
    _submit(book, "j1", 2.0)
    assert book.snapshot(2.0).vehicles[0].state == "battery_swap"
    assert _assigned(_status(book, 1.0, 5.0)) == []  # the crew has not confirmed
    reply, _ = book.operator(OperatorCommand(command="battery_swapped", vehicle_id="uav1"), 30.0)
    assert reply.ok
    assert _assigned(_status(book, 0.99, 31.0)) == [("uav1", "j1")]


def test_a_swap_confirmed_for_a_vehicle_not_waiting_is_refused_in_one_line() -> None:
    book = _book()
    _status(book, 0.9, 1.0)
    reply, _ = book.operator(OperatorCommand(command="battery_swapped", vehicle_id="uav1"), 2.0)
    assert not reply.ok and reply.message == "uav1 is not waiting for a battery swap"
    reply, _ = book.operator(OperatorCommand(command="battery_swapped"), 2.0)
    assert not reply.ok and reply.error is not None and reply.error.field == "vehicle_id"


def test_a_vehicle_at_its_reserve_is_sent_for_a_swap_with_an_empty_queue() -> None:
    book = _book()
    eff = _status(book, 0.2, 1.0)
    (swap,) = [e for e in eff.events if e.kind == "battery_swap"]
    assert swap.message == "uav1: swap its battery (20% left, at the reserve (20%))"
    assert book.snapshot(1.0).vehicles[0].state == "battery_swap"


def test_a_job_no_full_pack_can_take_is_given_to_no_one_rather_than_swapping_for_ever() -> None:
    book = _book()
    _status(book, 1.0, 1.0)
    eff = _submit(book, "long", 2.0, estimate_s=3600.0)  # an hour: more than a pack holds
    assert _assigned(eff) == [] and not any(e.kind == "battery_swap" for e in eff.events)
    assert book.snapshot(2.0).vehicles[0].state == "idle"


def test_the_etas_count_a_swap_where_the_charge_runs_out() -> None:
    def j2_eta(charge: float) -> float | None:
        book = _book()
        _status(book, charge, 0.0)
        assert _assigned(_submit(book, "j1", 0.0)) == [("uav1", "j1")]
        _submit(book, "j2", 0.0)
        (j2,) = [j for j in book.snapshot(0.0).jobs if j.job_id == "j2"]
        return j2.eta_s

    # j1: approach 11 s, writes 10 s, back 9 s; j2 approaches 11 s after: 41 s
    assert j2_eta(0.9) == pytest.approx(41.0)
    # 22.5 %: j1 leaves 20.7 %, j2 would leave 18.9 %: the 60 s swap comes first
    after_j1 = charge_after(QUAD, 0.225, job_energy_wh(QUAD, JobLeg(11.0, 10.0, 9.0)))
    assert shortfall(QUAD, after_j1, JobLeg(11.0, 10.0, 9.0), 0.2) is not None
    assert j2_eta(0.225) == pytest.approx(41.0 + 60.0)


def test_the_crews_turnaround_is_the_median_of_its_swaps() -> None:
    swaps = Swaps(time_scale=2.0, swap_s=60.0)
    assert swaps.turnaround_s == 60.0
    for vid, since_s, done_s in (("a", 0.0, 10.0), ("b", 0.0, 40.0), ("c", 5.0, 25.0)):
        swaps.begin(vid, 0.1, since_s)
        assert swaps.swapped(vid, done_s)
    assert swaps.turnaround_s == pytest.approx(40.0)  # show seconds: 20, 80, 40 at scale 2
    assert not swaps.swapped("a", 50.0)  # not waiting
    assert not swaps.heard("a", 0.12) and swaps.heard("a", 1.0)


@settings(max_examples=150, deadline=None)
@given(
    charge=st.floats(0.0, 1.0),
    estimate_s=st.floats(1.0, 900.0),
    reserve=st.floats(0.0, 0.6),
)
def test_no_job_is_dispatched_whose_energy_return_and_reserve_exceed_the_charge(
    charge: float, estimate_s: float, reserve: float
) -> None:
    book = _book(reserve)
    _status(book, charge, 0.0)
    eff = _submit(book, "j1", 1.0, estimate_s=estimate_s)
    flown = BatteryState(charge_fraction=charge)
    steps = 200
    for _ in range(steps):  # fly it on the pack model, independently of charge_after
        flown = discharge(QUAD.pack, flown, QUAD.power_w.hover_w, (20.0 + estimate_s) / steps)
    if _assigned(eff):
        assert flown.charge_fraction >= reserve - 2e-3
    else:
        state = book.snapshot(1.0).vehicles[0].state
        enough_when_full = shortfall(QUAD, 1.0, JobLeg(11.0, estimate_s, 9.0), reserve) is None
        at_reserve = charge <= reserve  # sent for a swap, job or not
        assert state == ("battery_swap" if enough_when_full or at_reserve else "idle")


def test_the_show_files_battery_section_is_validated(tmp_path: object) -> None:
    text = """
show_id: t
boards: [{id: b1, center_m_enu: [0, 0, 0], size_m: [1, 1], writing_area_m: [0.5, 0.5]}]
vehicles: [{id: uav1, board: b1, home_m_enu: [0, -1, 0]}]
battery: {reserve_fraction: 1.5}
"""
    with pytest.raises(ShowError, match="reserve_fraction"):
        parse_show(text)
    show = parse_show(text.replace("1.5", "0.3"))
    assert show.battery.reserve_fraction == 0.3 and show.battery.swap_s == 60.0

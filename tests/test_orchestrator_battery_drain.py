"""Each vehicle's drain learned from its own reports (``orchestrator/battery_drain.py``), used in
dispatch (``orchestrator/battery_swaps.py``), and the batteries' state kept across a restart
(``orchestrator/battery_records.py`` in ``orchestrator/store.py``).

The vehicles here fly on the pack model (:mod:`sim.battery`) at a true draw their kind's model
does not know, and report as the agent does: the charge to the percent, the flight time to 10 s
(``vehicle_agent/battery.py``, ``vehicle_agent/flight_day.py``)."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bus.messages import OperatorCommand, SubmitRequest, VehicleStateName, VehicleStatus
from orchestrator import battery_swaps
from orchestrator.batteries import JobLeg, charge_after, job_energy_wh, shortfall
from orchestrator.battery_drain import PRIOR_S, Drains
from orchestrator.core import Book, CoreConfig, Effects
from orchestrator.fleet import EtaModel, VehicleInfo
from orchestrator.store import JobStore
from sim.battery import BatteryState, discharge
from vehicles.batteries import kind_battery

QUAD = kind_battery("quadrotor-brush")
HOVER_W = QUAD.power_w.hover_w
VEHICLES = (VehicleInfo("uav1", "quadrotor-brush", "b1"),)
FLIGHT = ("taking_off", "writing", "returning", "landing")


def _config() -> CoreConfig:
    return CoreConfig(
        show_id="t",
        vehicles=VEHICLES,
        eta=EtaModel(time_scale=1.0),
        batteries=(("quadrotor-brush", QUAD),),
        battery_reserve_fraction=0.2,
        battery_swap_s=60.0,
    )


class Vehicle:
    """uav1 on the pack model, drawing ``true_w`` in the air and its avionics on the ground,
    reporting as the agent does: a status whenever a figure it carries changes."""

    def __init__(self, book: Book, true_w: float, charge: float = 1.0) -> None:
        self.book, self.true_w = book, true_w
        self.pack = BatteryState(charge_fraction=charge)
        self.flight_s = self.now_s = 0.0
        self.book.liveliness("uav1", True, 0.0)
        self.said: VehicleStatus | None = None
        self.report("idle")

    def report(self, state: VehicleStateName) -> Effects | None:
        status = VehicleStatus(
            vehicle_id="uav1",
            kind="quadrotor-brush",
            state=state,
            battery_fraction=round(self.pack.charge_fraction, 2),
            flight_s_today=10.0 * round(self.flight_s / 10.0),
        )
        if status == self.said:
            return None
        self.said = status
        return self.book.status(status, self.now_s)

    def spend(self, seconds: float, state: VehicleStateName) -> None:
        airborne = state in FLIGHT
        for _ in range(round(seconds)):
            power_w = self.true_w if airborne else QUAD.power_w.rest_w
            self.pack = discharge(QUAD.pack, self.pack, power_w, 1.0)
            self.now_s += 1.0
            self.flight_s += 1.0 if airborne else 0.0
            self.report(state)

    def fly(self, seconds: float, ground_s: float = 30.0) -> None:
        """A flight through every airborne state, then ``ground_s`` idle."""
        for state in FLIGHT:
            self.spend(seconds / len(FLIGHT), state)
        self.spend(ground_s, "idle")


def test_a_vehicle_drawing_half_as_much_again_as_its_model_is_learned_to_a_few_percent() -> None:
    # 1.5 x 105 W, 80 s flights with 10 minutes idle (6 W) between: the idle draw is no
    # job's cost, and the reports' rounding errs only at each flight's ends
    book = Book(_config(), now_s=0.0)
    vehicle = Vehicle(book, 1.5 * HOVER_W)
    for _ in range(6):
        vehicle.fly(80.0, ground_s=600.0)
    sums = book.drains.sums["uav1"]
    assert sums.flown_s == pytest.approx(480.0, abs=20.0)
    assert sums.observed_wh / sums.model_wh == pytest.approx(1.5, rel=0.04)
    weight = sums.flown_s / (PRIOR_S + sums.flown_s)  # the model keeps PRIOR_S of flight
    assert book.drains.factor("uav1") == pytest.approx(1.0 + 0.5 * weight, rel=0.04)
    assert Vehicle(Book(_config(), now_s=0.0), HOVER_W).book.drains.factor("uav1") == 1.0


@settings(max_examples=30, deadline=None)
@given(true_over_model=st.floats(0.7, 3.0), flights=st.integers(4, 8))
def test_the_learned_drain_follows_the_true_one_within_the_reports_rounding(
    true_over_model: float, flights: int
) -> None:
    drains = Drains()
    state, flight_s = BatteryState(charge_fraction=1.0), 0.0
    drains.heard("v", QUAD, 1.0, 0.0, airborne=False)
    for _ in range(flights):
        for second in range(60):
            state = discharge(QUAD.pack, state, true_over_model * HOVER_W, 1.0)
            flight_s += 1.0
            landed = second == 59
            charge = round(state.charge_fraction, 2)
            drains.heard("v", QUAD, charge, 10.0 * round(flight_s / 10.0), airborne=not landed)
    sums = drains.sums["v"]
    # each flight's two ends err by half a percent of charge at most: 1 % of the pack in all
    slack_wh = flights * 0.01 * QUAD.pack.energy_wh(1.0)
    assert abs(sums.observed_wh - true_over_model * sums.model_wh) < slack_wh + 0.02 * sums.model_wh


def test_dispatch_prices_a_job_at_the_vehicles_own_drain_and_the_swap_keeps_it() -> None:
    book = Book(_config(), now_s=0.0)
    vehicle = Vehicle(book, 1.6 * HOVER_W)
    for _ in range(8):
        vehicle.fly(80.0)
    factor = book.drains.factor("uav1")
    assert factor == pytest.approx(1.0 + 0.6 * 640.0 / (PRIOR_S + 640.0), rel=0.05)
    # a 60 s job (11 s approach, 40 s writing, 9 s back) at 25 %: the kind's model lands it
    # at 21.0 %, above the 20 % reserve; the vehicle's true draw lands it at 18.6 %
    leg = JobLeg(11.0, 40.0, 9.0)
    charge = 0.25
    energy_wh = job_energy_wh(QUAD, leg)
    assert charge_after(QUAD, charge, energy_wh) > 0.2  # today's code flew it
    truth = BatteryState(charge_fraction=charge)
    for _ in range(60):
        truth = discharge(QUAD.pack, truth, 1.6 * HOVER_W, 1.0)
    assert truth.charge_fraction < 0.2  # and it would land under the reserve
    assert charge_after(QUAD, charge, factor * energy_wh) < 0.2
    vehicle.pack = BatteryState(charge_fraction=charge)
    vehicle.report("idle")
    _, eff = book.submit("j1", SubmitRequest(text="L"), label="L", estimate_s=40.0, now_s=2000.0)
    assert not [c for _, c in eff.commands if c.command == "assign"]
    (swap,) = [e for e in eff.events if e.kind == "battery_swap"]
    assert f"drawing {factor:.2f}x its model" in swap.message
    # the crew's swap resets the charge, not what was learned
    reply, _ = book.operator(OperatorCommand(command="battery_swapped", vehicle_id="uav1"), 2060.0)
    assert reply.ok
    vehicle.pack, vehicle.now_s = BatteryState(charge_fraction=1.0), 2061.0
    eff = vehicle.report("idle")
    assert eff is not None
    assert [c.job.job_id for _, c in eff.commands if c.command == "assign" and c.job] == ["j1"]
    assert book.drains.factor("uav1") == factor


def test_a_glitch_or_a_recovering_estimate_teaches_nothing() -> None:
    drains = Drains()
    drains.heard("v", QUAD, 0.80, 0.0, airborne=True)
    drains.heard("v", QUAD, 0.10, 10.0, airborne=True)  # 70 % in 10 s: more than the pack gives
    drains.heard("v", QUAD, 0.80, 10.0, airborne=True)  # back: a fresh pack as far as it goes
    drains.heard("v", QUAD, 0.81, 20.0, airborne=True)  # a voltage estimate recovering
    drains.heard("v", QUAD, 0.80, 20.0, airborne=True)
    sums = drains.sums["v"]
    assert sums.observed_wh == 0.0 and sums.flown_s == 10.0  # the glitch's 10 s drop out too
    assert drains.heard("v", QUAD, 0.80, 30.0, airborne=False)  # landed: worth storing


def test_swaps_waits_the_crews_pace_and_the_drains_outlive_a_restart(tmp_path: Path) -> None:
    book = Book(_config(), now_s=0.0)
    vehicle = Vehicle(book, 1.5 * HOVER_W)
    for _ in range(3):
        vehicle.fly(80.0)
    vehicle.pack = BatteryState(charge_fraction=0.19)
    vehicle.report("idle")
    book.tick(vehicle.now_s)  # at the reserve: sent for a swap
    assert book.snapshot(vehicle.now_s).vehicles[0].state == "battery_swap"
    factor = book.drains.factor("uav1")
    with JobStore(tmp_path / "show.sqlite3") as store:
        store.save(batteries=battery_swaps.records(book))
    with JobStore(tmp_path / "show.sqlite3") as store:
        stored = store.load()
    again = Book(_config(), now_s=vehicle.now_s + 5.0, batteries=stored.batteries)
    again.liveliness("uav1", True, vehicle.now_s + 5.0)
    assert again.drains.factor("uav1") == factor
    # PX4 SITL refills its pack at disarm: the full report does not end the wait for the crew
    status = VehicleStatus(vehicle_id="uav1", kind="quadrotor-brush", state="idle",
                           battery_fraction=1.0, flight_s_today=vehicle.flight_s)  # fmt: skip
    again.status(status, vehicle.now_s + 6.0)
    (summary,) = again.snapshot(vehicle.now_s + 6.0).vehicles
    assert summary.state == "battery_swap" and "19% left" in summary.message
    command = OperatorCommand(command="battery_swapped", vehicle_id="uav1")
    reply, _ = again.operator(command, vehicle.now_s + 50.0)
    assert reply.ok  # the crew's confirmation is taken: it was waiting
    assert again.swaps.turnaround_s == pytest.approx(50.0)  # from the first wait, not the restart
    with JobStore(tmp_path / "show.sqlite3") as store:
        store.save(batteries=battery_swaps.records(again))
        assert store.load().batteries.turnarounds_s == (pytest.approx(50.0),)


def _lowest_landing(true_over_model: float, *, learn: bool, jobs: int = 60) -> float:
    """Fly ``jobs`` jobs (11 s approach, 20-80 s of writing, 9 s back) on one vehicle, each
    taken only if dispatch's check lets it (else the crew swaps its pack first); the lowest
    charge it landed with."""
    book = Book(_config(), now_s=0.0)
    vehicle = Vehicle(book, true_over_model * HOVER_W)
    lowest = 1.0
    for k in range(jobs):
        leg = JobLeg(11.0, 20.0 + (37.0 * k) % 60.0, 9.0)
        factor = book.drains.factor("uav1") if learn else 1.0
        charge = round(vehicle.pack.charge_fraction, 2)
        if shortfall(QUAD, charge, leg, 0.2, factor) is not None:
            vehicle.pack = BatteryState(charge_fraction=1.0)  # the crew's fresh pack
            vehicle.report("idle")
        vehicle.fly(leg.approach_s + leg.writing_s + leg.back_s, ground_s=20.0)
        lowest = min(lowest, vehicle.pack.charge_fraction)
    return lowest


@pytest.mark.parametrize("true_over_model", [1.6, 2.0, 3.0])
def test_in_a_closed_loop_no_vehicle_lands_under_its_reserve_once_its_drain_is_learned(
    true_over_model: float,
) -> None:
    # the kind's model alone lands a vehicle that draws more under the 20 % reserve, as
    # ArduCopter SITL's did (6-10 %); learned, it lands within a report's rounding (1 %) of it
    assert _lowest_landing(true_over_model, learn=False) < 0.19
    assert _lowest_landing(true_over_model, learn=True) > 0.195

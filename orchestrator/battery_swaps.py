"""Battery swaps on the :class:`~orchestrator.core.Book` (pure): a ready vehicle whose charge
cannot take the job it would be given, or that is at its reserve, is sent for a swap; the crew's
``battery_swapped`` ends the wait; its fresh pack's first report lets it take jobs again; the
ETAs spend each vehicle's charge. A job is priced at the vehicle's own learned drain
(``orchestrator/battery_drain.py``). The waits, the crew's pace and the drains are stored with
the settings, so a restart keeps them (``orchestrator/battery_records.py``). The arithmetic is
``orchestrator/batteries.py``'s."""

from __future__ import annotations

from typing import TYPE_CHECKING

from bus.messages import AIRBORNE_STATES, CommandReply, ErrorInfo, OperatorCommand, VehicleCommand
from orchestrator.batteries import EtaCharges, JobLeg, charge_after, job_energy_wh, shortfall
from orchestrator.battery_records import BatteryRecords
from orchestrator.fleet import VehicleView, waiting_on_ground
from orchestrator.jobs import Job

if TYPE_CHECKING:
    from orchestrator.book_protocol import BookProtocol
    from orchestrator.core_types import Effects
    from sim.battery import VehicleBattery


def battery_of(book: BookProtocol, vehicle_id: str) -> VehicleBattery | None:
    """The battery of the vehicle's kind (None: its kind has none in the config)."""
    kind = book.vehicles[vehicle_id].info.kind
    return dict(book.config.batteries).get(kind)


def leg(book: BookProtocol, job: Job, vehicle_id: str) -> JobLeg:
    """How long ``job`` keeps ``vehicle_id`` busy, show seconds."""
    model = book.config.eta
    writing_s = book.kinds.writing_s_on(job, vehicle_id)
    return JobLeg(model.before_write_s, writing_s, model.after_write_s)


def lacks(book: BookProtocol, view: VehicleView, job: Job | None) -> str | None:
    """Why ``view``'s vehicle must swap its battery before ``job`` (None: job or not, it need
    not): its charge would fall below the reserve, or is at the reserve already."""
    battery = battery_of(book, view.info.vehicle_id)
    charge, reserve = view.battery_fraction, book.config.battery_reserve_fraction
    if battery is None or charge is None:
        return None
    if charge <= reserve:
        return f"{100 * charge:.0f}% left, at the reserve ({100 * reserve:.0f}%)"
    if job is None:
        return None
    vid = view.info.vehicle_id
    return shortfall(battery, charge, leg(book, job, vid), reserve, book.drains.factor(vid))


def fits_full(book: BookProtocol, vehicle_id: str, job: Job) -> bool:
    """Whether ``job`` fits ``vehicle_id``'s full pack with the reserve (a job that does not is
    never given to it: a swap would not help)."""
    battery = battery_of(book, vehicle_id)
    if battery is None:
        return True
    reserve = book.config.battery_reserve_fraction
    factor = book.drains.factor(vehicle_id)
    return shortfall(battery, 1.0, leg(book, job, vehicle_id), reserve, factor) is None


def send_for_swap(
    book: BookProtocol, eff: Effects, view: VehicleView, why: str, now_s: float
) -> None:
    """``view``'s vehicle (on the ground, ready) waits for the crew's swap."""
    vid = view.info.vehicle_id
    view.swap_reason = why
    book.swaps.begin(vid, view.battery_fraction, now_s)
    eff.fleet_changed = eff.settings_changed = True
    book.event(eff, now_s, "warning", "battery_swap", f"{vid}: swap its battery ({why})",
               vehicle_id=vid)  # fmt: skip


def check_reserves(book: BookProtocol, eff: Effects, now_s: float) -> None:
    """Send every ready vehicle at or under its reserve for a swap (a queue empty or not)."""
    for view in book.vehicles.values():
        if waiting_on_ground(view, now_s) and (why := lacks(book, view, None)) is not None:
            send_for_swap(book, eff, view, why, now_s)


def heard(book: BookProtocol, eff: Effects, view: VehicleView) -> bool:
    """A status came (its battery, flight time and state on ``view``): its drain learned from
    it; True if a swapped vehicle's fresh pack has now reported, which ends its wait."""
    vid = view.info.vehicle_id
    battery = battery_of(book, vid)
    if battery is not None:
        airborne = view.state in AIRBORNE_STATES
        charge, flown_s = view.battery_fraction, view.flight_s_today
        if book.drains.heard(vid, battery, charge, flown_s, airborne=airborne):
            eff.settings_changed = True  # a flight's drain, kept across a restart
    if not book.swaps.heard(vid, view.battery_fraction):
        return False
    view.swap_reason = ""
    eff.settings_changed = True
    return True


def swapped(book: BookProtocol, cmd: OperatorCommand, eff: Effects, now_s: float) -> CommandReply:
    """The crew's ``battery_swapped VEHICLE``: the vehicle's agent is told (a simulated vehicle
    gets its full pack); the vehicle takes jobs once its fresh pack has reported."""
    assert cmd.vehicle_id is not None  # checked by the caller
    vid = cmd.vehicle_id
    view = book.vehicles[vid]
    if not book.swaps.swapped(vid, now_s):
        message = f"{vid} is not waiting for a battery swap"
        info = ErrorInfo(code="bad_state", message=message, field="vehicle_id")
        return CommandReply(ok=False, message=message, error=info)
    eff.commands.append((vid, VehicleCommand(command="battery_swapped")))
    eff.settings_changed = True
    if vid not in book.swaps.fresh_above:
        view.swap_reason = ""
    else:
        view.swap_reason = "swapped; waiting for its fresh battery to report"
    eff.fleet_changed = True
    return CommandReply(ok=True, message=f"{vid}: battery swapped")


def eta_charges(book: BookProtocol, now_s: float) -> EtaCharges:
    """The vehicles' charge for the ETAs (``orchestrator/fleet.py:queue_etas``)."""
    reserve = book.config.battery_reserve_fraction

    def after(job: Job, vehicle_id: str, charge: float) -> float:
        battery = battery_of(book, vehicle_id)
        if battery is None:
            return charge
        energy_wh = job_energy_wh(battery, leg(book, job, vehicle_id))
        return charge_after(battery, charge, energy_wh * book.drains.factor(vehicle_id))

    charge = {
        vid: view.battery_fraction
        for vid, view in book.vehicles.items()
        if view.battery_fraction is not None and battery_of(book, vid) is not None
    }
    waiting = {vid: book.swaps.free_at_s(vid, now_s) for vid in book.swaps.waiting}
    for vid in waiting:
        charge[vid] = 1.0
    return EtaCharges(charge, after, reserve, book.swaps.turnaround_s, waiting)


def records(book: BookProtocol) -> BatteryRecords:
    """What a restart keeps of the batteries (stored with the settings)."""
    reasons = {vid: view.swap_reason for vid, view in book.vehicles.items()}
    swaps, turnarounds_s = book.swaps.records(reasons)
    return BatteryRecords(swaps=swaps, turnarounds_s=turnarounds_s, drains=book.drains.records())


def restore(book: BookProtocol, stored: BatteryRecords) -> None:
    """Take up what :func:`records` kept (vehicles the show no longer has are dropped)."""
    swaps = [r for r in stored.swaps if r.vehicle_id in book.vehicles]
    book.swaps.restore(swaps, stored.turnarounds_s)
    for record in swaps:
        book.vehicles[record.vehicle_id].swap_reason = record.reason

"""Battery swaps on the :class:`~orchestrator.core.Book` (pure): a ready vehicle whose charge
cannot take the job it would be given, or that is at its reserve, is sent for a swap; the crew's
``battery_swapped`` ends the wait; its fresh pack's first report lets it take jobs again; the
ETAs spend each vehicle's charge. The arithmetic is ``orchestrator/batteries.py``'s."""

from __future__ import annotations

from typing import TYPE_CHECKING

from bus.messages import CommandReply, ErrorInfo, OperatorCommand, VehicleCommand
from orchestrator.batteries import EtaCharges, JobLeg, charge_after, job_energy_wh, shortfall
from orchestrator.fleet import VehicleView, waiting_on_ground
from orchestrator.jobs import Job

if TYPE_CHECKING:
    from orchestrator.core import Book
    from orchestrator.core_types import Effects
    from sim.battery import VehicleBattery


def battery_of(book: Book, vehicle_id: str) -> VehicleBattery | None:
    """The battery of the vehicle's kind (None: its kind has none in the config)."""
    kind = book.vehicles[vehicle_id].info.kind
    return dict(book.config.batteries).get(kind)


def leg(book: Book, job: Job, vehicle_id: str) -> JobLeg:
    """How long ``job`` keeps ``vehicle_id`` busy, show seconds."""
    model = book.config.eta
    writing_s = book.kinds.writing_s_on(job, vehicle_id)
    return JobLeg(model.before_write_s, writing_s, model.after_write_s)


def lacks(book: Book, view: VehicleView, job: Job | None) -> str | None:
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
    return shortfall(battery, charge, leg(book, job, view.info.vehicle_id), reserve)


def fits_full(book: Book, vehicle_id: str, job: Job) -> bool:
    """Whether ``job`` fits ``vehicle_id``'s full pack with the reserve (a job that does not is
    never given to it: a swap would not help)."""
    battery = battery_of(book, vehicle_id)
    if battery is None:
        return True
    reserve = book.config.battery_reserve_fraction
    return shortfall(battery, 1.0, leg(book, job, vehicle_id), reserve) is None


def send_for_swap(book: Book, eff: Effects, view: VehicleView, why: str, now_s: float) -> None:
    """``view``'s vehicle (on the ground, ready) waits for the crew's swap."""
    vid = view.info.vehicle_id
    view.swap_reason = why
    book.swaps.begin(vid, view.battery_fraction, now_s)
    eff.fleet_changed = True
    book.event(eff, now_s, "warning", "battery_swap", f"{vid}: swap its battery ({why})",
               vehicle_id=vid)  # fmt: skip


def check_reserves(book: Book, eff: Effects, now_s: float) -> None:
    """Send every ready vehicle at or under its reserve for a swap (a queue empty or not)."""
    for view in book.vehicles.values():
        if waiting_on_ground(view, now_s) and (why := lacks(book, view, None)) is not None:
            send_for_swap(book, eff, view, why, now_s)


def heard(book: Book, view: VehicleView) -> bool:
    """A status came (its battery on ``view``); True if a swapped vehicle's fresh pack has now
    reported, which ends its wait."""
    if not book.swaps.heard(view.info.vehicle_id, view.battery_fraction):
        return False
    view.swap_reason = ""
    return True


def swapped(book: Book, cmd: OperatorCommand, eff: Effects, now_s: float) -> CommandReply:
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
    if vid not in book.swaps.fresh_above:
        view.swap_reason = ""
    else:
        view.swap_reason = "swapped; waiting for its fresh battery to report"
    eff.fleet_changed = True
    return CommandReply(ok=True, message=f"{vid}: battery swapped")


def eta_charges(book: Book, now_s: float) -> EtaCharges:
    """The vehicles' charge for the ETAs (``orchestrator/fleet.py:queue_etas``)."""
    reserve = book.config.battery_reserve_fraction

    def after(job: Job, vehicle_id: str, charge: float) -> float:
        battery = battery_of(book, vehicle_id)
        if battery is None:
            return charge
        return charge_after(battery, charge, job_energy_wh(battery, leg(book, job, vehicle_id)))

    charge = {
        vid: view.battery_fraction
        for vid, view in book.vehicles.items()
        if view.battery_fraction is not None and battery_of(book, vid) is not None
    }
    waiting = {vid: book.swaps.free_at_s(vid, now_s) for vid in book.swaps.waiting}
    for vid in waiting:
        charge[vid] = 1.0
    return EtaCharges(charge, after, reserve, book.swaps.turnaround_s, waiting)

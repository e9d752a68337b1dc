"""Batteries in dispatch (pure): what a job costs a vehicle's battery, whether it may take the
job and keep the show's reserve, the swaps the crew makes and how long they take.

A job costs its vehicle the energy of its approach (``EtaModel.before_write_s``, counted at the
kind's transit draw although part of it is planning on the ground), of its writing (the planned
duration at the writing draw) and of its return and landing (``after_write_s``, transit draw),
times what the vehicle draws over its kind's model as learned from its own reports
(``orchestrator/battery_drain.py``); the energy is turned into charge along the pack's own
open-circuit curve from the charge the vehicle reported (:mod:`sim.battery`: each Wh costs more
charge as the voltage falls), with the internal resistance's loss at that draw. A vehicle whose
charge after the job would fall below ``battery.reserve_fraction`` takes no job: it is sent for a
swap (it is on the ground: vehicles land after every job) and waits, in ``battery_swap``, for the
crew's ``battery_swapped``; then until it reports a charge above the one it was sent with (a fresh
pack; a vehicle that reports no battery is let go at once). The crew's turnaround (from the
vehicle's wait to the confirmation, show seconds) is the median of its last
:data:`TURNAROUNDS_KEPT`, ``battery.swap_s`` until there is one; the ETAs count a swap wherever a
vehicle's charge would run out.
"""

from __future__ import annotations

import statistics
from collections import deque
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass

from orchestrator.battery_records import SwapRecord
from orchestrator.jobs import Job
from sim.battery import VehicleBattery

TURNAROUNDS_KEPT = 10
"""Swaps the crew's turnaround is the median of: the day's pace, not the morning's."""
NEWTON_STEPS = 20
"""Most Newton steps of :func:`charge_after` (it converges in 3-5 to 1e-12 of the charge)."""
FRESH_MARGIN = 0.05
"""A swapped vehicle counts as fresh once it reports this much more charge than before."""


@dataclass(frozen=True)
class JobLeg:
    """How long each part of a job keeps a vehicle busy, show seconds."""

    approach_s: float
    """From assignment to the start of writing (``EtaModel.before_write_s``)."""
    writing_s: float
    """Writing (the planned duration on the vehicle's kind)."""
    back_s: float
    """Return and landing (``EtaModel.after_write_s``)."""


def job_energy_wh(battery: VehicleBattery, leg: JobLeg) -> float:
    """Energy in [Wh] a job takes from the pack."""
    power = battery.power_w
    flying_j = power.transit_w * (leg.approach_s + leg.back_s)
    return (flying_j + power.writing_w * leg.writing_s) / 3600.0


def charge_after(battery: VehicleBattery, charge_fraction: float, energy_wh: float) -> float:
    """Charge fraction left after drawing ``energy_wh`` [Wh] from ``charge_fraction``: the charge
    whose open-circuit energy is that much lower (Newton's method on the pack's energy curve,
    whose slope is the open-circuit voltage times the capacity: the ETAs call this for every
    queued job and vehicle), the internal resistance's share at the transit draw added to the
    energy; 0 when it runs out."""
    pack = battery.pack
    current_a = pack.current_a(charge_fraction, battery.power_w.transit_w)
    v_oc = pack.open_circuit_v(charge_fraction)
    delivered = pack.terminal_v(charge_fraction, current_a) / v_oc
    target_wh = pack.energy_wh(charge_fraction) - energy_wh / delivered
    if target_wh <= 0.0:
        return 0.0
    capacity_ah = pack.capacity_mah / 1000.0
    charge = charge_fraction
    for _ in range(NEWTON_STEPS):
        step = (pack.energy_wh(charge) - target_wh) / (pack.open_circuit_v(charge) * capacity_ah)
        charge = min(charge_fraction, max(0.0, charge - step))
        if abs(step) < 1e-12:
            break
    return charge


def shortfall(
    battery: VehicleBattery,
    charge_fraction: float,
    leg: JobLeg,
    reserve_fraction: float,
    drain_factor: float = 1.0,
) -> str | None:
    """Why a vehicle with ``charge_fraction`` may not take a job (one line), None if it may:
    the charge left after it must be at least ``reserve_fraction``; ``drain_factor``: what the
    vehicle draws over its kind's model (``orchestrator/battery_drain.py``)."""
    left = charge_after(battery, charge_fraction, drain_factor * job_energy_wh(battery, leg))
    if left >= reserve_fraction:
        return None
    drawing = f", drawing {drain_factor:.2f}x its model" if drain_factor != 1.0 else ""
    return (
        f"{100 * charge_fraction:.0f}% left, the next job would leave {100 * left:.0f}% "
        f"(reserve {100 * reserve_fraction:.0f}%{drawing})"
    )


class Swaps:
    """Vehicles waiting for the crew's battery swap, or for their fresh pack's first report,
    and the crew's pace."""

    def __init__(self, *, time_scale: float, swap_s: float) -> None:
        self.time_scale = time_scale
        self._default_turnaround_s = swap_s
        self.waiting: dict[str, float] = {}
        """Vehicle id -> Unix time [s] since which it waits for the crew."""
        self._sent_with: dict[str, float] = {}
        """Vehicle id -> the charge it was sent for its swap with (a fresh pack may report
        before the crew confirms: an autopilot restarted by the swap, PX4 SITL's pack refilled
        at disarm)."""
        self.fresh_above: dict[str, float] = {}
        """Vehicle id -> the charge it was sent with: swapped, and not yet heard with more."""
        self._turnarounds_s: deque[float] = deque(maxlen=TURNAROUNDS_KEPT)

    @property
    def turnaround_s(self) -> float:
        """The crew's expected turnaround, show seconds."""
        if not self._turnarounds_s:
            return self._default_turnaround_s
        return statistics.median(self._turnarounds_s)

    def begin(self, vehicle_id: str, charge_fraction: float | None, now_s: float) -> None:
        """``vehicle_id``, with ``charge_fraction`` left, waits for the crew from now (kept if
        it already did)."""
        if vehicle_id not in self.waiting:
            self.waiting[vehicle_id] = now_s
            if charge_fraction is not None:
                self._sent_with[vehicle_id] = charge_fraction

    def swapped(self, vehicle_id: str, now_s: float) -> bool:
        """The crew confirmed a fresh pack in ``vehicle_id``; True if it was waiting for one (its
        turnaround is counted). It then waits for a report above the charge it was sent with."""
        since_s = self.waiting.pop(vehicle_id, None)
        if since_s is None:
            return False
        self._turnarounds_s.append((now_s - since_s) * self.time_scale)
        sent_with = self._sent_with.pop(vehicle_id, None)
        if sent_with is not None:
            self.fresh_above[vehicle_id] = sent_with
        return True

    def heard(self, vehicle_id: str, charge_fraction: float | None) -> bool:
        """A status with ``charge_fraction``; True if it ends the wait for a fresh pack."""
        before = self.fresh_above.get(vehicle_id)
        if before is None:
            return False
        if charge_fraction is not None and charge_fraction < min(before + FRESH_MARGIN, 1.0):
            return False
        del self.fresh_above[vehicle_id]
        return True

    def records(
        self, reasons: Mapping[str, str]
    ) -> tuple[tuple[SwapRecord, ...], tuple[float, ...]]:
        """What a restart keeps: each vehicle waiting (``reasons``: vehicle id -> why it was sent)
        and the crew's turnarounds (``orchestrator/battery_records.py``)."""
        vids = sorted(self.waiting.keys() | self.fresh_above.keys())
        swaps = tuple(
            SwapRecord(
                vid,
                reasons.get(vid, ""),
                waiting_since_s=self.waiting.get(vid),
                sent_with_fraction=self._sent_with.get(vid),
                fresh_above_fraction=self.fresh_above.get(vid),
            )
            for vid in vids
        )
        return swaps, tuple(self._turnarounds_s)

    def restore(self, swaps: Iterable[SwapRecord], turnarounds_s: Iterable[float]) -> None:
        """Take up what :meth:`records` kept."""
        for record in swaps:
            vid = record.vehicle_id
            if record.waiting_since_s is not None:
                self.waiting[vid] = record.waiting_since_s
            if record.sent_with_fraction is not None:
                self._sent_with[vid] = record.sent_with_fraction
            if record.fresh_above_fraction is not None:
                self.fresh_above[vid] = record.fresh_above_fraction
        self._turnarounds_s.extend(turnarounds_s)

    def free_at_s(self, vehicle_id: str, now_s: float) -> float:
        """When ``vehicle_id`` may take a job as far as its battery goes, Unix time [s] (an
        estimate while the crew is on its way: never before now)."""
        since_s = self.waiting.get(vehicle_id)
        if since_s is None:
            return now_s
        return max(now_s, since_s + self.turnaround_s / self.time_scale)


@dataclass
class EtaCharges:
    """The vehicles' charge as the ETAs' list scheduling spends it, job after job
    (``orchestrator/fleet.py:queue_etas``): a job its vehicle's charge cannot take with the reserve
    waits for a swap, after which the vehicle starts from a full pack."""

    charge: dict[str, float]
    """Vehicle id -> charge fraction now, for the vehicles that report one."""
    after: Callable[[Job, str, float], float]
    """(job, vehicle id, charge before) -> charge after writing the job on that vehicle."""
    reserve_fraction: float
    swap_s: float
    """The crew's turnaround, show seconds."""
    free_at_s: dict[str, float]
    """Vehicle id -> Unix time [s] its swap should be done, for those waiting for one."""

    def swap_first(self, job: Job, vehicle_id: str) -> bool:
        """Whether ``vehicle_id`` would need a swap before ``job``."""
        charge = self.charge.get(vehicle_id)
        return charge is not None and self.after(job, vehicle_id, charge) < self.reserve_fraction

    def spend(self, job: Job, vehicle_id: str) -> None:
        """``vehicle_id`` writes ``job`` (after a swap, if it needs one)."""
        charge = self.charge.get(vehicle_id)
        if charge is not None:
            start = 1.0 if self.swap_first(job, vehicle_id) else charge
            self.charge[vehicle_id] = self.after(job, vehicle_id, start)

"""Each vehicle's battery drain, learned from its own reports (pure).

Dispatch prices a job with its kind's pack model (``orchestrator/batteries.py``), but a vehicle
draws what its airframe, its pack's age and the day make it draw: on ArduCopter SITL the Airshow
vehicles landed at 6-10 % with a 20 % reserve (issue 31's 50-job run), its simulated copter
drawing more than the model's 105 W. So each vehicle's statuses teach a factor over its model:

- **What it drew.** Between two statuses of a vehicle that was airborne at the first
  (``AIRBORNE_STATES``), the open-circuit energy between the two charges it reported (the pack
  model's curve, :meth:`~sim.battery.LipoPack.energy_wh`); what the model would have drawn is its
  transit draw over the flight time between them (``flight_s_today``), from the first charge
  (:func:`~orchestrator.batteries.charge_after`). Both are summed over every flight; the sums
  telescope, so the reports' rounding (1 % of charge, 10 s of flight) errs at each flight's two
  ends only, not at every status.
- **What does not count.** The ground between jobs (an idle vehicle draws its avionics' few
  watts, no job's cost); a charge risen by more than ``FRESH_MARGIN`` (a fresh pack, or PX4
  SITL's refilled at disarm) or a flight time that fell (an agent restarted, a new day): counting
  starts afresh from that status, the charge reset and the learned drain kept; a smaller rise (a
  voltage-based estimate recovering after the load) counts as nothing drawn; a drop faster than
  the pack can deliver (a report's glitch).
- **The factor** leans on the model (factor 1) by :data:`PRIOR_S` seconds of flight:
  ``(PRIOR_S + flown_s * observed / model) / (PRIOR_S + flown_s)``.

No floor or ceiling: a battery monitor stuck at one figure would read as a low factor, but its
vehicle is never sent for a swap either way (its charge never falls), so a bound would protect
nothing.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from orchestrator.batteries import FRESH_MARGIN, charge_after
from orchestrator.battery_records import DrainRecord
from sim.battery import VehicleBattery

PRIOR_S = 60.0
"""Seconds of flight the kind's model weighs as, against a vehicle's own: about one Airshow job's
flight (11 s approach, 9 s back: ``EtaModel``'s medians, and some 40 s of writing). Kept short on
purpose: the reports' rounding costs a fraction of one job's charge (±0.5 % of charge at each end
of an 80 s flight that draws about 5 %, on the 4S 3000 mAh pack), while the prior keeps the
model's whole error on every job until it is outweighed; after 5 such flights a vehicle's own
drain weighs 87 %."""
FLIGHT_STEP_S = 10.0
"""A status's flight time is rounded to this, [s] (``vehicle_agent/flight_day.py``)."""


@dataclass
class DrainSums:
    """One vehicle's flights so far."""

    observed_wh: float = 0.0
    """Open-circuit energy its reports showed drawn, [Wh]."""
    model_wh: float = 0.0
    """What its kind's model would have drawn over the same flight time, [Wh]."""
    flown_s: float = 0.0
    """The flight time counted, [s] of agent time."""

    @property
    def factor(self) -> float:
        """The vehicle's drain over its model's, the model weighing :data:`PRIOR_S`."""
        if self.model_wh <= 0.0:
            return 1.0
        observed = self.flown_s * self.observed_wh / self.model_wh
        return (PRIOR_S + observed) / (PRIOR_S + self.flown_s)


@dataclass(frozen=True)
class _Heard:
    charge_fraction: float
    flight_s: float
    airborne: bool


class Drains:
    """Every vehicle's learned drain; fed with each status (:meth:`heard`)."""

    def __init__(self, records: Iterable[DrainRecord] = ()) -> None:
        self.sums: dict[str, DrainSums] = {
            r.vehicle_id: DrainSums(r.observed_wh, r.model_wh, r.flown_s) for r in records
        }
        self._last: dict[str, _Heard] = {}
        """Vehicle id -> what counting goes on from (its last status, the charge never above
        the one before but for a fresh pack): not stored, a restart starts afresh."""

    def factor(self, vehicle_id: str) -> float:
        """What ``vehicle_id`` draws over its kind's model (1 until it has flown)."""
        sums = self.sums.get(vehicle_id)
        return 1.0 if sums is None else sums.factor

    def heard(
        self,
        vehicle_id: str,
        battery: VehicleBattery,
        charge_fraction: float | None,
        flight_s: float | None,
        *,
        airborne: bool,
    ) -> bool:
        """A status of ``vehicle_id`` (its kind's ``battery``): ``charge_fraction`` left, off
        the ground ``flight_s`` [s] today, ``airborne`` now. True when it ends a flight that
        counted (worth storing)."""
        last = self._last.pop(vehicle_id, None)
        if charge_fraction is None or flight_s is None:
            return False
        if last is not None and last.charge_fraction < charge_fraction <= (
            last.charge_fraction + FRESH_MARGIN
        ):
            charge_fraction = last.charge_fraction  # a recovery, not a fresh pack
        self._last[vehicle_id] = _Heard(charge_fraction, flight_s, airborne)
        if last is None or not last.airborne:
            return False
        flown_s = flight_s - last.flight_s
        if charge_fraction > last.charge_fraction or flown_s < 0.0:
            return False
        pack, before = battery.pack, last.charge_fraction
        observed_wh = pack.energy_wh(before) - pack.energy_wh(charge_fraction)
        if observed_wh * 3600.0 > pack.max_power_w(before) * (flown_s + FLIGHT_STEP_S):
            return False
        model_left = charge_after(battery, before, battery.power_w.transit_w * flown_s / 3600.0)
        sums = self.sums.setdefault(vehicle_id, DrainSums())
        sums.observed_wh += observed_wh
        sums.model_wh += pack.energy_wh(before) - pack.energy_wh(model_left)
        sums.flown_s += flown_s
        return not airborne

    def records(self) -> tuple[DrainRecord, ...]:
        """What a restart keeps (``orchestrator/battery_records.py``)."""
        return tuple(
            DrainRecord(vid, s.observed_wh, s.model_wh, s.flown_s)
            for vid, s in sorted(self.sums.items())
        )

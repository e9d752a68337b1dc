"""The agent's figures of the vehicle's day for its status (pure): time off the ground today,
the link's losses."""

from __future__ import annotations

from dataclasses import dataclass

import msgspec

from bus.messages import VehicleStatus
from vehicle_agent.backends.base import VehicleSnapshot

FLIGHT_ROUND_S = 10.0
"""The status carries the flight time to this in [s]: a status published on change goes out
every 10 s of flight for it, not every tick."""


@dataclass
class FlightDay:
    """Time off the ground on one day, counted tick by tick; a new day starts from 0."""

    day: int | None = None
    """The day counted (any number that changes at midnight, e.g. the local ordinal)."""
    flight_s: float = 0.0
    """Time off the ground on ``day`` in [s] of agent time."""
    last_s: float | None = None
    """Agent time in [s] of the last tick counted."""

    def tick(self, snapshot: VehicleSnapshot, now_s: float, day: int) -> None:
        """A control period that began at agent time ``now_s`` [s] on ``day`` ended in
        ``snapshot``: the time since the last tick counts if the vehicle was off the ground."""
        if day != self.day:
            self.day, self.flight_s = day, 0.0
        if self.last_s is not None and not snapshot.on_ground:
            self.flight_s += max(0.0, now_s - self.last_s)
        self.last_s = now_s


def with_day(
    status: VehicleStatus, snapshot: VehicleSnapshot | None, flight: FlightDay
) -> VehicleStatus:
    """``status`` with the flight time today and the link's losses, rounded (10 s, the
    percent) so that a status published on change goes out when a figure a person reads does."""
    health = None if snapshot is None else snapshot.health
    loss = None if health is None else health.link_loss_fraction
    return msgspec.structs.replace(
        status,
        link_loss_fraction=None if loss is None else round(loss, 2),
        flight_s_today=FLIGHT_ROUND_S * round(flight.flight_s / FLIGHT_ROUND_S),
    )

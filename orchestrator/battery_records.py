"""What the orchestrator keeps of its vehicles' batteries across a restart (stored with the
settings, ``orchestrator/store.py``): who waits for the crew's swap or for its fresh pack, the
crew's turnarounds, and each vehicle's learned drain (``orchestrator/battery_drain.py``).

A restart that forgot them would let a vehicle whose pack its autopilot refilled (PX4 SITL at
disarm) fly without the crew's swap, send a swapped vehicle for a second swap while its old pack's
figure still reports, and price jobs again at the kind's model until each vehicle had flown again.
"""

from __future__ import annotations

import msgspec


class SwapRecord(msgspec.Struct, frozen=True):
    """One vehicle sent for a swap: waiting for the crew, or swapped and waiting for its fresh
    pack to report."""

    vehicle_id: str
    reason: str
    """Why it was sent, as the console shows it."""
    waiting_since_s: float | None = None
    """Unix time [s] since which it waits for the crew; None: the crew has confirmed."""
    sent_with_fraction: float | None = None
    """The charge it was sent with (while it waits for the crew)."""
    fresh_above_fraction: float | None = None
    """Swapped: the charge its fresh pack must report more than (``batteries.FRESH_MARGIN``)."""


class DrainRecord(msgspec.Struct, frozen=True):
    """One vehicle's drain learned so far (``orchestrator/battery_drain.py``)."""

    vehicle_id: str
    observed_wh: float
    """Open-circuit energy [Wh] its reports showed drawn while it flew."""
    model_wh: float
    """What its kind's model draws over the same flights, [Wh]."""
    flown_s: float
    """The flight time those cover, [s] of agent time."""


class BatteryRecords(msgspec.Struct, frozen=True):
    """All of it, one settings value."""

    swaps: tuple[SwapRecord, ...] = ()
    turnarounds_s: tuple[float, ...] = ()
    """The crew's latest swap turnarounds, show seconds, oldest first."""
    drains: tuple[DrainRecord, ...] = ()

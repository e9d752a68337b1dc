"""What the console's views read from the model: frozen rows and alerts."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from bus.messages import JobState

QueueSection = Literal["awaiting", "queued", "active", "done", "failed"]
"""Sections of the queue view, in display order."""


@dataclass(frozen=True)
class VehicleRow:
    """One vehicle as the fleet table shows it."""

    vehicle_id: str
    kind: str
    state: str
    """A vehicle state name, ``lost`` when its token vanished, or ``unknown`` before any news."""
    board_id: str | None
    job_id: str | None
    job_label: str | None
    """The character being written (the job's label)."""
    progress: float
    """Fraction of the job flown, 0..1."""
    tracking_error_m: float | None
    """Latest tracking error in [m]; None before the first telemetry."""
    battery_fraction: float | None
    """0..1 when known."""
    battery_minutes_left: float | None
    """Minutes until its battery is empty, when known."""
    link_age_s: float | None
    """Seconds since the vehicle's last telemetry or status; None if never heard."""
    stale: bool
    """Heard from before, but not within the show's ``lost_after_s``."""
    over_threshold: bool
    """Writing with a tracking error above the show's alert threshold."""
    message: str
    position_m_enu: tuple[float, float, float] | None
    held: bool = False
    """Landed or stopped by the operator: it takes no job until released (``u``)."""
    paused: bool = False
    """Paused by the operator: no new job until resumed (``P``)."""
    surface: str = ""
    """What it writes on (``board``, ``wall``, ``floor``), from the show file; empty if unknown."""
    force_n: float | None = None
    """Latest measured normal contact force in [N], for kinds that sense it."""
    force_reference_n: float | None = None
    """Latest wanted normal contact force in [N], for kinds that control it."""
    force_off: bool = False
    """Writing with a contact force further from its target than the console's alert margin."""
    link_loss_fraction: float | None = None
    """Share of its autopilot's messages lost on its link, when it has one."""
    preflight: str = ""
    """Why it may not take off now (its preflight's failing check); empty: it may."""
    flight_s_today: float | None = None
    """Its time off the ground today in [s], when reported."""


@dataclass(frozen=True)
class QueueRow:
    """One job in the queue view."""

    section: QueueSection
    job: JobState


@dataclass(frozen=True)
class Alert:
    """Something the operator must see now."""

    key: str
    """Stable identity, e.g. ``lost:uav1``; acknowledged alerts stay hidden until it clears."""
    kind: Literal[
        "vehicle_lost",
        "vehicle_fault",
        "tracking_error",
        "force_error",
        "job_failed",
        "awaiting_approval",
        "fresh_sheet",
        "battery_swap",
        "orchestrator_lost",
        "vehicle_held",
        "show_alert",
    ]
    """``vehicle_held`` and ``show_alert`` (any other) come from the orchestrator's open alerts."""
    message: str

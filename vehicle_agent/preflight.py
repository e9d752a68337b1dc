"""The agent's preflight (pure): measured figures in, the first failing check's reason out.

Before a vehicle takes a job (at start, after a battery swap, after a fault is cleared, and
between jobs: whenever it waits on the ground) the agent checks, in this order: its link to
the autopilot (heartbeat age, messages lost), the autopilot's estimator and the mocap it is fed,
its geofences (the agent's own, and the autopilot's read back at connect), its battery against
the show's reserve, its clock against the orchestrator's, and last the autopilot's own pre-arm
checks. A reason is set in the status's ``preflight``, in words a show operator reads; the
orchestrator gives the vehicle no job while it is (``orchestrator/fleet.py``). A figure not
measured (None: a simulated vehicle has no link, a clock not yet compared) is not checked.
The bounds and their sources are the show's ``preflight`` section (``showfile/services.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from vehicle_agent.backends.base import LinkHealth


@dataclass(frozen=True)
class PreflightLimits:
    """The bounds of the checks (the show's ``preflight`` and ``battery`` sections)."""

    link_age_max_s: float = 2.0
    """Oldest autopilot heartbeat in [s]."""
    link_loss_max_fraction: float = 0.05
    """Most autopilot messages lost on the link, 0..1."""
    mocap_age_max_s: float = 0.2
    """Oldest mocap pose forwarded to the autopilot in [s]."""
    battery_reserve_fraction: float = 0.20
    """Charge the battery must hold above, 0..1 (the show's reserve)."""
    clock_offset_max_s: float = 0.05
    """Largest offset in [s] of the agent's clock from the orchestrator's."""
    fence_required: bool = True
    """The agent must have its own geofence."""


@dataclass(frozen=True)
class PreflightReadings:
    """What was measured just now; None: not measured (that check is skipped)."""

    health: LinkHealth | None = None
    """The backend's link and estimator figures."""
    battery_fraction: float | None = None
    """Charge left, 0..1."""
    has_fence: bool = True
    """The agent has its own geofence."""
    clock_offset_s: float | None = None
    """The agent's clock minus the orchestrator's, [s]."""
    autopilot: str | None = None
    """The autopilot's own reason it would not arm, in its words."""


def preflight_problem(readings: PreflightReadings, limits: PreflightLimits) -> str | None:
    """The first failing check's reason, in words for a show operator; None: all pass."""
    health = readings.health or LinkHealth()
    return (
        _link(health, limits)
        or _estimator(health, limits)
        or _fences(health, readings, limits)
        or _battery(readings.battery_fraction, limits)
        or _clock(readings.clock_offset_s, limits)
        or readings.autopilot
    )


def _link(health: LinkHealth, limits: PreflightLimits) -> str | None:
    age_s, loss = health.link_age_s, health.link_loss_fraction
    if age_s is not None and age_s > limits.link_age_max_s:
        return f"link: no autopilot heartbeat for {age_s:.1f} s (limit {limits.link_age_max_s:g} s)"
    if loss is not None and loss > limits.link_loss_max_fraction:
        bound = 100 * limits.link_loss_max_fraction
        return f"link: {100 * loss:.1f}% of the autopilot's messages lost (limit {bound:g}%)"
    return None


def _estimator(health: LinkHealth, limits: PreflightLimits) -> str | None:
    """The mocap the autopilot fuses first: missing, it is the cause of the estimator's missing
    position (which an ESTIMATOR_STATUS says only once it has come, at 0.5-1 Hz)."""
    age_s = health.mocap_age_s
    if age_s is not None and math.isinf(age_s):
        return "mocap: no pose sent to the autopilot yet"
    if age_s is not None and age_s > limits.mocap_age_max_s:
        bound_ms = 1e3 * limits.mocap_age_max_s
        return f"mocap: last pose sent {1e3 * age_s:.0f} ms ago (limit {bound_ms:.0f} ms)"
    if health.estimator is not None:
        return f"estimator: {health.estimator}"
    return None


def _fences(health: LinkHealth, readings: PreflightReadings, limits: PreflightLimits) -> str | None:
    if limits.fence_required and not readings.has_fence:
        return "geofence: none loaded"
    if health.fence is not None:
        return f"geofence: {health.fence}"
    return None


def _battery(charge: float | None, limits: PreflightLimits) -> str | None:
    reserve = limits.battery_reserve_fraction
    if charge is None or charge > reserve:
        return None
    return f"battery: {100 * charge:.0f}% left, at or below the {100 * reserve:.0f}% reserve"


def _clock(offset_s: float | None, limits: PreflightLimits) -> str | None:
    if offset_s is None or abs(offset_s) <= limits.clock_offset_max_s:
        return None
    bound_ms = 1e3 * limits.clock_offset_max_s
    return (
        f"clock: {1e3 * offset_s:+.0f} ms off the orchestrator's (limit {bound_ms:.0f} ms): "
        "synchronise it (NTP/PTP)"
    )

"""The per-tick safety verdict of one vehicle: deviation and geofence, decided in pure code.

The job runner asks the guard once per control period whether the vehicle may go on
(:meth:`SafetyGuard.check`), and once per plan whether the plan stays inside the fence
(:meth:`SafetyGuard.check_plan`). The guard only judges; the runner decides what to do.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from vehicle_agent.backends.base import Setpoint, Vec3, VehicleSnapshot
from vehicle_agent.safety.geofence import BOUNDARY_TOLERANCE_M, FenceWatch
from vehicle_agent.safety.limits import SafetyLimits
from vehicles.deviation import DeviationMonitor

TRACKED_PHASES = frozenset({"transit", "settle", "write"})
"""Phases of a job in which the tracking error is bounded."""
FENCED_EXEMPT = frozenset({"ground", "preflight", "climb", "stopped", "land", "fence_hold"})
"""Phases in which the fence is not checked: on the ground, in the autopilot's own take-off
climb above home (no setpoint can be given there; the autopilot's fence is the line), or
already stopping."""

AbortCode = Literal["deviation", "geofence"]


@dataclass(frozen=True)
class Breach:
    """A bound the vehicle broke this tick."""

    code: AbortCode
    """``deviation`` or ``geofence`` (also the ErrorInfo code of the failed job)."""
    message: str
    """One sentence for a person."""
    position_m_enu: Vec3
    """Where the vehicle was in [m], ENU."""


class SafetyGuard:
    """Deviation monitor and geofence of one vehicle."""

    def __init__(self, limits: SafetyLimits) -> None:
        self.limits = limits
        self.monitor = DeviationMonitor(limits.deviation)
        self.last_error_m = 0.0
        """Tracking error in [m] seen at the last tracked tick."""
        self._watch = None if limits.fence is None else FenceWatch(limits.fence)

    def check(
        self, phase: str, snapshot: VehicleSnapshot, reference: Setpoint | None, now_s: float
    ) -> Breach | None:
        """Judge one tick: ``reference`` is the setpoint the vehicle was tracking in the period
        that ended at ``snapshot``. A breach is reported once; call :meth:`reset` to re-arm."""
        position = snapshot.position_m_enu
        watch = self._watch
        if watch is not None and phase not in FENCED_EXEMPT and not snapshot.on_ground:
            outside_m = watch.distance_outside_m(position)
            if outside_m > BOUNDARY_TOLERANCE_M:
                outside_mm, _ = figures_apart(outside_m * 1e3, 0.0)
                where = ", ".join(f"{v:.2f}" for v in position)
                message = f"outside its geofence by {outside_mm} mm at ({where}) m"
                return Breach("geofence", message, position)
        if phase not in TRACKED_PHASES or reference is None:
            self.monitor.reset()
            return None
        if self.monitor.trip is not None:
            return None  # reported already
        error = math.dist(position, reference.position_m_enu)
        self.last_error_m = error
        trip = self.monitor.update(error, now_s)
        if trip is None:
            return None
        return Breach("deviation", f"{trip.message} ({phase})", position)

    def reset(self) -> None:
        """Re-arm the deviation monitor (a new job)."""
        self.monitor.reset()

    def check_plan(self, positions_m_enu: np.ndarray, start_m_enu: Vec3) -> str | None:
        """Why a plan leaves the fence (its reference samples and the hover point it starts
        from), or None when it stays inside."""
        fence = self.limits.fence
        if fence is None:
            return None
        if not fence.contains(start_m_enu):
            return f"the hover point {_fmt(start_m_enu)} m is outside the vehicle's geofence"
        index = fence.first_outside(positions_m_enu)
        if index is None:
            return None
        point = tuple(float(v) for v in np.asarray(positions_m_enu)[index])
        return (
            f"the plan leaves the vehicle's geofence at sample {index} {_fmt(point)} m "
            f"(fence {fence.floor_z_m:.2f}..{fence.ceiling_z_m:.2f} m high)"
        )


def _fmt(p: tuple[float, ...]) -> str:
    return "(" + ", ".join(f"{v:.2f}" for v in p) + ")"


def figures_apart(value: float, bound: float, decimals: int = 1) -> tuple[str, str]:
    """``value`` and the ``bound`` it failed, with ``decimals`` decimals or as many more as tell
    them apart (up to 9), so that a message never shows a failed figure equal to its bound (a
    geofence breach of "0.0 mm", a settling error "outside" a tolerance it prints equal to)."""
    while decimals < 9 and f"{value:.{decimals}f}" == f"{bound:.{decimals}f}":
        decimals += 1
    return f"{value:.{decimals}f}", f"{bound:.{decimals}f}"

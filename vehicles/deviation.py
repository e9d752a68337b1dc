"""Tracking deviation: an error above a bound for longer than a short window trips (pure).

The monitor is fed one tracking error per control period with the agent time; it trips once the
error has stayed above ``bound_m`` for more than ``window_s`` (a single noisy sample does not), and
stays tripped until :meth:`DeviationMonitor.reset`. Time is injected: the same code runs in batch
simulation and on the vehicle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class DeviationLimit:
    """How far and how long a vehicle may stray from its reference."""

    bound_m: float
    """Largest tracking error in [m]."""
    window_s: float
    """Time in [s] the error may stay above the bound before the monitor trips."""

    def __post_init__(self) -> None:
        if not self.bound_m > 0.0 or not self.window_s >= 0.0:
            raise ValueError(
                f"deviation bound must be > 0 and window >= 0, got {self.bound_m} m, "
                f"{self.window_s} s"
            )


@dataclass(frozen=True)
class DeviationTrip:
    """The verdict of a tripped monitor."""

    error_m: float
    """Tracking error in [m] at the moment it tripped."""
    peak_m: float
    """Largest error in [m] since it went above the bound."""
    above_since_s: float
    """Agent time in [s] the error went above the bound."""
    tripped_at_s: float
    """Agent time in [s] it tripped."""
    limit: DeviationLimit
    """The limit that was broken."""

    @property
    def message(self) -> str:
        """One sentence for a person."""
        return (
            f"tracking error {self.error_m:.3f} m (peak {self.peak_m:.3f} m) above the bound "
            f"{self.limit.bound_m:.3f} m for {self.tripped_at_s - self.above_since_s:.2f} s"
        )


class DeviationMonitor:
    """Watches one vehicle's tracking error, one sample per control period."""

    def __init__(self, limit: DeviationLimit) -> None:
        self.limit = limit
        self._above_since_s: float | None = None
        self._peak_m = 0.0
        self.trip: DeviationTrip | None = None
        """Set once tripped (until :meth:`reset`)."""

    def reset(self) -> None:
        """Forget the history (a new phase or a new job begins)."""
        self._above_since_s = None
        self._peak_m = 0.0
        self.trip = None

    def update(self, error_m: float, now_s: float) -> DeviationTrip | None:
        """Take the error in [m] at agent time ``now_s`` in [s]; the trip when it trips now or
        has tripped before, else None. A NaN error counts as above the bound."""
        if self.trip is not None:
            return self.trip
        if error_m <= self.limit.bound_m:  # False for NaN
            self._above_since_s = None
            self._peak_m = 0.0
            return None
        if self._above_since_s is None:
            self._above_since_s = now_s
        self._peak_m = max(self._peak_m, error_m) if math.isfinite(error_m) else math.inf
        if now_s - self._above_since_s >= self.limit.window_s:
            self.trip = DeviationTrip(
                error_m=error_m,
                peak_m=self._peak_m,
                above_since_s=self._above_since_s,
                tripped_at_s=now_s,
                limit=self.limit,
            )
        return self.trip

"""The safety limits one vehicle's agent works with, and the writing-bounds verdict (pure)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

from showfile.geofence import Geofence
from vehicles.deviation import DeviationLimit
from vehicles.verdict import WritingBounds

AbortPolicy = Literal["hold", "land"]


@dataclass(frozen=True)
class SafetyLimits:
    """Everything the job runner needs to keep a vehicle safe (from the show's ``safety``)."""

    deviation: DeviationLimit = field(default_factory=lambda: DeviationLimit(0.15, 0.3))
    """Tracking-error bound while a job flies."""
    fence: Geofence | None = None
    """The vehicle's geofence (None: none, e.g. unit tests of other things)."""
    writing: WritingBounds = field(default_factory=WritingBounds)
    """Bounds of a job reported ``done``."""
    abort_policy: AbortPolicy = "land"
    """After an abort: hover in place (``hold``) or return and land (``land``)."""
    abort_hold_s: float = 10.0
    """How long in [s] a ``hold`` lasts before the vehicle returns and lands."""
    abort_backoff_s: float = 30.0
    """After an abort the vehicle takes no job for this long in [s] (agent time)."""
    fence_hold_s: float = 2.0
    """Outside its fence the vehicle holds this long in [s], then lands where it is."""
    settle_tolerance_m: float = 0.01
    """Before writing, the vehicle must hold the start this close in [m]..."""
    settle_hold_s: float = 1.0
    """...for this long in [s] without a break..."""
    settle_timeout_s: float = 3.0
    """...within this long in [s] per approach..."""
    settle_attempts: int = 2
    """...and gets this many approaches; then the job is handed back (``not_settled``)."""

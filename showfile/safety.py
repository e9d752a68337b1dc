"""The show's ``safety`` section: the bounds a vehicle must keep, and what it does when it cannot.

Every field has a default, so a show file without a ``safety`` section gets these bounds:

- **deviation**: a tracking error above ``deviation_bound_m`` for longer than
  ``deviation_window_s`` while a job flies (approach, settle, writing) aborts it: the brush is
  lifted, the vehicle holds or lands (``abort_policy``), the job is reported ``failed`` with code
  ``deviation`` and an alert is raised;
- **geofence**: each vehicle keeps inside the convex hull of its board, its home and the transit
  between them, grown by ``fence_margin_m``, from the ground up to its cruise height plus
  ``fence_ceiling_margin_m``; a plan that leaves it is refused before take-off (code
  ``geofence``), a vehicle found outside holds ``fence_hold_s`` and lands where it is;
- **writing bounds**: a job is ``done`` only when its pen-down RMSE is at most
  ``rmse_pen_down_max_m`` and its ink IoU (when the backend knows the brush) at least ``iou_min``;
  otherwise it is ``failed`` with code ``writing_bounds``;
- **settling**: the brush goes down only once the vehicle has held the start within
  ``settle_tolerance_m`` for ``settle_hold_s`` without a break; it has ``settle_timeout_s`` per
  approach and ``settle_attempts`` approaches, after which the job goes back to the queue (code
  ``not_settled``).
"""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field

AbortPolicy = Literal["hold", "land"]
"""After an abort, with the brush lifted: ``hold`` hovers where it is (for ``abort_hold_s``, or
until the operator lands it), ``land`` returns above home and lands."""


class SafetySettings(BaseModel):
    """Bounds of tracking, space and writing quality, and the response to breaking them."""

    model_config = ConfigDict(frozen=True, extra="forbid", use_attribute_docstrings=True)

    deviation_bound_m: float = Field(default=0.15, gt=0.0)
    """Largest tracking error in [m] (vehicle to its reference) while a job flies."""
    deviation_window_s: float = Field(default=0.3, ge=0.0)
    """How long in [s] the error may stay above the bound before the job is aborted."""
    abort_policy: AbortPolicy = "land"
    """What the vehicle does once the brush is lifted after an abort."""
    abort_hold_s: float = Field(default=10.0, gt=0.0)
    """With ``abort_policy: hold``: hover this long in [s] waiting for the operator, then land."""
    abort_backoff_s: float = Field(default=30.0, ge=0.0)
    """After an abort the vehicle takes no job for this long in [s]."""
    fence_margin_m: float = Field(default=0.5, ge=0.0)
    """Horizontal margin in [m] of the geofence around the board, the home and the transit."""
    fence_ceiling_margin_m: float = Field(default=0.5, ge=0.0)
    """Height in [m] of the geofence's ceiling above the cruise height."""
    fence_hold_s: float = Field(default=2.0, ge=0.0)
    """A vehicle found outside its geofence holds this long in [s], then lands where it is."""
    autopilot_fence: bool = True
    """Also set the autopilot's own fence at connect (MAVLink vehicles), as a second line:
    ArduPilot FENCE_*, PX4 GF_*; its radius and ceiling are the geofence's plus
    ``autopilot_fence_margin_m``."""
    autopilot_fence_margin_m: float = Field(default=1.0, ge=0.0)
    """How much larger in [m] the autopilot's fence is than the agent's own."""
    rmse_pen_down_max_m: float = Field(default=0.05, gt=0.0)
    """Largest pen-down RMSE in [m] of a job reported ``done``."""
    iou_min: float = Field(default=0.3, ge=0.0, le=1.0)
    """Smallest ink IoU of a job reported ``done`` (checked when the backend knows the brush)."""
    settle_tolerance_m: float = Field(default=0.01, gt=0.0)
    """Before writing the vehicle must hold the start of the plan this close, in [m]..."""
    settle_hold_s: float = Field(default=1.0, ge=0.0)
    """...for this long in [s] without a break. A vehicle that swings about the start passes
    through the tolerance without holding it: ArduCopter SITL after a transit swung +-1 cm at
    about 0.5 Hz, and a one-sample check put the brush down as the swing crossed the start, 1.4
    cm off a moment later. A swing of period T is inside for less than T/2."""
    settle_timeout_s: float = Field(default=3.0, gt=0.0)
    """Time in [s] one approach may take to settle."""
    settle_attempts: int = Field(default=2, ge=1)
    """Approaches flown before the job is handed back as ``not_settled``."""

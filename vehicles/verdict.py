"""When a written job counts as ``done``: its writing within the show's bounds (pure).

One rule for the live agent's reports (``vehicle_agent.runner_io``) and the batch flight of
``skyquill fly``, so a job is never ``done`` in one and broken in the other.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class WritingBounds:
    """What a written job must meet to be reported ``done``."""

    rmse_pen_down_max_m: float = 0.05
    """Largest pen-down RMSE in [m]."""
    iou_min: float = 0.3
    """Smallest ink IoU (checked only when the IoU is known)."""


def writing_verdict(rmse_pen_down_m: float, iou: float | None, bounds: WritingBounds) -> str | None:
    """Why a written job broke its bounds, or None when it met them (NaN breaks them)."""
    problems = []
    if not rmse_pen_down_m <= bounds.rmse_pen_down_max_m:
        problems.append(
            f"pen-down RMSE {rmse_pen_down_m:.4f} m above {bounds.rmse_pen_down_max_m:.4f} m"
        )
    if iou is not None and not (math.isfinite(iou) and iou >= bounds.iou_min):
        problems.append(f"ink IoU {iou:.3f} below {bounds.iou_min:.3f}")
    return "; ".join(problems) or None

"""When a written job counts as ``done``: its writing within the show's bounds (pure).

One rule for the live agent's reports (``vehicle_agent.runner_io``) and the batch flight of
``skyquill fly``, so a job is never ``done`` in one and broken in the other. A job is ``done``
only on what was measured: a pen that never came down (no pen-down RMSE), no ink on the target
(IoU 0) or a plan flown in part breaks the bounds, whatever they are.
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


def writing_verdict(
    rmse_pen_down_m: float | None,
    iou: float | None,
    bounds: WritingBounds,
    *,
    flown_fraction: float = 1.0,
) -> str | None:
    """Why a written job broke its bounds, or None when it met them (NaN breaks them).

    ``rmse_pen_down_m`` None: the pen never came down; ``iou`` None: the backend does not know
    its brush (the IoU is then not checked); ``flown_fraction``: how much of the plan was flown
    (0..1, below 1 the job was written in part)."""
    if rmse_pen_down_m is None:
        return "nothing written: the pen never came down"
    problems = []
    if not flown_fraction >= 1.0:
        problems.append(f"written in part: {flown_fraction:.0%} of the plan flown")
    if not rmse_pen_down_m <= bounds.rmse_pen_down_max_m:
        problems.append(
            f"pen-down RMSE {rmse_pen_down_m:.4f} m above {bounds.rmse_pen_down_max_m:.4f} m"
        )
    if iou is not None and math.isfinite(iou) and iou <= 0.0:
        problems.append("no ink on the target (IoU 0)")
    elif iou is not None and not (math.isfinite(iou) and iou >= bounds.iou_min):
        problems.append(f"ink IoU {iou:.3f} below {bounds.iou_min:.3f}")
    return "; ".join(problems) or None

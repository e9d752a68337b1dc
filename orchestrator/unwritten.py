"""What a ``done`` report may not claim (pure): the orchestrator's floor under the agents' verdict.

An agent reports ``done`` only within the show's writing bounds (``vehicles/verdict.py``, applied
by ``vehicle_agent.runner_io.result_report``). Whatever an agent's bounds or version, the
orchestrator records no job ``done`` whose own metrics say nothing was written: a pen that never
came down (no pen-down RMSE), no ink on the target (IoU 0) or a plan flown in part. Such a report
is recorded as ``failed`` (``writing_bounds``) instead. A report without metrics claims no
figure and is taken as it is.
"""

from __future__ import annotations

import math

from bus.messages import JobMetrics
from vehicles.verdict import WritingBounds, writing_verdict

ANY_WRITING = WritingBounds(rmse_pen_down_max_m=math.inf, iou_min=0.0)
"""Bounds that let any measured writing by: what is left is the verdict's floor."""


def unwritten(metrics: JobMetrics | None) -> str | None:
    """Why a job with ``metrics`` cannot be ``done`` whatever the show's bounds (None: it may)."""
    if metrics is None:
        return None
    return writing_verdict(
        metrics.rmse_pen_down_m,
        metrics.iou,
        ANY_WRITING,
        flown_fraction=metrics.flown_fraction,
    )

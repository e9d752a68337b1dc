"""The ground writer's report figure: the floor, the tracking error and the wheels' slip."""

from __future__ import annotations

import warnings

import matplotlib

matplotlib.use("Agg")

import numpy as np
from matplotlib.figure import Figure

from vehicles.kind import FlownWriting, WritingPlan, WritingScore
from vehicles.omni_wheel.geometry import WHEEL_GROUP


def build_report(plan: WritingPlan, flown: FlownWriting, score: WritingScore, title: str) -> Figure:
    """Three panels: marker path on the floor against the pen-down reference; marker error
    against time; |slip ratio| per wheel group (eq. 19) against time."""
    fig = Figure(figsize=(14, 4.5), layout="constrained")
    floor, error, slip = fig.subplots(1, 3)
    ref = plan.surface.to_surface(flown.reference_m_enu)
    marker = plan.surface.to_surface(flown.writing_point_m_enu)
    inked = flown.ink_width_m > 0.0
    floor.plot(ref[:, 0], ref[:, 1], color="0.8", lw=1, label="reference (pen up)")
    floor.plot(np.where(flown.pen_down, ref[:, 0], np.nan), ref[:, 1], color="k", lw=3,
               label="reference (pen down)")  # fmt: skip
    floor.plot(np.where(inked, marker[:, 0], np.nan), marker[:, 1], color="tab:red", lw=1,
               label="marker (ink)")  # fmt: skip
    floor.set_aspect("equal")
    floor.set_xlabel("floor x [m]")
    floor.set_ylabel("floor y [m]")
    floor.legend(loc="best", fontsize=7)
    floor.set_title(f"IoU {score.iou:.3f}" if score.iou is not None else "no ink")
    err_mm = 1e3 * np.linalg.norm(
        flown.writing_point_m_enu[:, :2] - flown.reference_m_enu[:, :2], axis=1
    )
    error.plot(flown.t_s, err_mm, lw=0.8)
    error.set_xlabel("t [s]")
    error.set_ylabel("marker error [mm]")
    error.set_title(f"pen-down RMSE {1e3 * score.rmse_pen_down_m:.1f} mm")
    ratios = flown.extra.get("slip")
    if ratios is not None:
        for group in ("front", "middle", "rear"):
            cols = [i for i, g in enumerate(WHEEL_GROUP) if g == group]
            with warnings.catch_warnings():  # a group may have no moving wheel at a tick
                warnings.simplefilter("ignore", RuntimeWarning)
                slip.plot(
                    flown.t_s, 100.0 * np.nanmean(ratios[:, cols], axis=1), lw=0.8, label=group
                )
        slip.legend(fontsize=7)
    slip.set_xlabel("t [s]")
    slip.set_ylabel("|slip ratio| [%] (eq. 19)")
    fig.suptitle(title)
    return fig

"""The ground writer's report figure: the floor, the tracking error and the wheels' slip. The
title is data (a public label): drawn literally (:func:`vehicles.picture.plain_heading`)."""

from __future__ import annotations

import warnings

import matplotlib

matplotlib.use("Agg")

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from vehicles.kind import FlownWriting, WritingPlan, WritingScore
from vehicles.omni_wheel.geometry import WHEEL_GROUP
from vehicles.picture import (
    LABEL_PT,
    TICK_PT,
    TITLE_PT,
    legend_below,
    plain_heading,
    report_figure,
)

HEIGHT_IN = 5.2
"""Height in [in] of the figure (1280 x 520 px at 100 dpi)."""
GROUP_COLOURS = {"front": "tab:blue", "middle": "tab:orange", "rear": "tab:green"}


def build_report(plan: WritingPlan, flown: FlownWriting, score: WritingScore, title: str) -> Figure:
    """Three panels: marker path on the floor against the pen-down reference; marker error
    against time; |slip ratio| per wheel group (eq. 19) against time where the run logged it
    (the batch simulation), else the marker's speed against the reference's (a live agent's
    trace has no wheel states)."""
    fig = report_figure(HEIGHT_IN)
    floor, error, third = fig.subplots(1, 3, width_ratios=(1.0, 1.2, 1.2))
    ref = plan.surface.to_surface(flown.reference_m_enu)
    marker = plan.surface.to_surface(flown.writing_point_m_enu)
    inked = flown.ink_width_m > 0.0
    floor.plot(ref[:, 0], ref[:, 1], color="0.75", lw=1.0, label="reference (pen up)")
    floor.plot(np.where(flown.pen_down, ref[:, 0], np.nan), ref[:, 1], color="k", lw=3.5,
               label="reference (pen down)")  # fmt: skip
    floor.plot(np.where(inked, marker[:, 0], np.nan), marker[:, 1], color="tab:red", lw=1.2,
               label="marker (ink)")  # fmt: skip
    floor.set_aspect("equal")
    floor.margins(0.06)
    floor.set_xlabel("floor x [m]", fontsize=LABEL_PT)
    floor.set_ylabel("floor y [m]", fontsize=LABEL_PT)
    iou = f"IoU {score.iou:.2f}" if score.iou is not None else "no ink"
    floor.set_title(f"floor: {iou}", fontsize=TITLE_PT - 1)
    err_mm = 1e3 * np.linalg.norm(
        flown.writing_point_m_enu[:, :2] - flown.reference_m_enu[:, :2], axis=1
    )
    error.plot(flown.t_s, err_mm, lw=1.0, color="tab:red")
    error.set_ylabel("marker error [mm]", fontsize=LABEL_PT)
    pen = score.rmse_pen_down_m
    rmse = "pen never down" if pen is None else f"pen-down RMSE {1e3 * pen:.1f} mm"
    error.set_title(f"marker error: {rmse}", fontsize=TITLE_PT - 1)
    ratios = flown.extra.get("slip")
    if ratios is not None:
        _slip_panel(third, flown.t_s, ratios)
    else:
        _speed_panel(third, flown)
    for ax in (floor, error, third):
        ax.tick_params(labelsize=TICK_PT)
    for ax in (error, third):
        ax.set_xlabel("time [s]", fontsize=LABEL_PT)
        lo, hi = ax.get_ylim()
        ax.fill_between(flown.t_s, lo, hi, where=flown.pen_down, color="0.5", alpha=0.15, lw=0,
                        label="pen down")  # fmt: skip
        ax.set_ylim(lo, hi)
    legend_below(fig)
    fig.suptitle(plain_heading(title), fontsize=TITLE_PT, parse_math=False)
    return fig


def _slip_panel(ax: Axes, t_s: np.ndarray, ratios: np.ndarray) -> None:
    """Mean |slip ratio| of each wheel group in [%] (NaN where no wheel of it turned)."""
    for group, colour in GROUP_COLOURS.items():
        cols = [i for i, g in enumerate(WHEEL_GROUP) if g == group]
        with warnings.catch_warnings():  # a group may have no moving wheel at a tick
            warnings.simplefilter("ignore", RuntimeWarning)
            mean = np.nanmean(ratios[:, cols], axis=1)
        ax.plot(t_s, 100.0 * mean, lw=1.0, color=colour, label=f"{group} wheels")
    ax.set_ylabel("|slip ratio| [%]", fontsize=LABEL_PT)
    ax.set_title("wheel slip (eq. 19), per group", fontsize=TITLE_PT - 1)


def _speed_panel(ax: Axes, flown: FlownWriting) -> None:
    """The marker's speed and its reference's in [m/s] (numerical derivatives)."""
    for name, path, colour in (
        ("reference speed", flown.reference_m_enu, "k"),
        ("marker speed", flown.writing_point_m_enu, "tab:red"),
    ):
        if flown.t_s.size > 1:
            speed = np.linalg.norm(np.gradient(path[:, :2], flown.t_s, axis=0), axis=1)
            ax.plot(flown.t_s, speed, lw=1.0, color=colour, label=name)
    ax.set_ylabel("speed [m/s]", fontsize=LABEL_PT)
    ax.set_title("speed (wheel slip is not logged live)", fontsize=TITLE_PT - 1)

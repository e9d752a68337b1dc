"""The flight report figure (``report.png``): tracking against time and the writing on the board.

Rows: position x, y, z against time (Phang 2015 Fig. 12: the writing point, i.e. the brush axis at
the nominal lever, and the body, which leans away from it on purpose); velocity x, y, z of the
body (Fig. 13); the input strokes, planned path and flown brush path on the board (Fig. 14), then
the written ink beside the target ink with their intersection over union (Guo 2024 section VII),
the three board panels on the same axes. Matplotlib's Agg backend only, never pyplot, so it runs
headless and in threads. The title is data (it may hold a label from the public): drawn
literally, never as mathtext (:func:`vehicles.picture.plain_heading`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from numpy.typing import NDArray

from planner.samples import TrajectorySamples
from vehicles.kind import FlownWriting
from vehicles.picture import (
    LABEL_PT,
    TICK_PT,
    TITLE_PT,
    legend_below,
    plain_heading,
    report_figure,
)
from vehicles.quadrotor_brush.metrics import (
    FlightMetrics,
    InkResult,
    body_of,
    tip_of,
    writing_point_error,
)
from vehicles.quadrotor_brush.params import BrushParams

FloatArray = NDArray[np.float64]

_AXES = "xyz"
HEIGHT_IN = 10.0
"""Height in [in] of the figure (1280 x 1000 px at 100 dpi): two rows of time plots, one of
square board panels, one legend below them all (none inside a panel, over the writing)."""
BOARD_MARGIN = 0.06
"""Free border around the writing on the board panels, as a fraction of its larger side."""


def _planned_velocity(flown: FlownWriting, planned: TrajectorySamples) -> FloatArray:
    """(K, 3) the plan's velocity in [m/s] at the flown ticks."""
    v = planned.velocity_mps_enu
    return np.stack([np.interp(flown.t_s, planned.t_s, v[:, c]) for c in range(3)], axis=1)


def _time_rows(
    fig: Figure, flown: FlownWriting, planned: TrajectorySamples, brush: BrushParams, grid: object
) -> None:
    t = flown.t_s - flown.t_s[0]
    pen = flown.pen_down
    writing = flown.reference_m_enu + writing_point_error(flown, brush)
    velocity = flown.extra.get("velocity_mps_enu", np.zeros((t.shape[0], 3)))
    rows = (
        ("writing point", "m", flown.reference_m_enu, writing, body_of(flown)),
        ("velocity", "m/s", _planned_velocity(flown, planned), velocity, None),
    )
    for r, (name, unit, ref, actual, body) in enumerate(rows):
        for c in range(3):
            ax = fig.add_subplot(grid[r, c])  # type: ignore[index]
            if body is not None:
                ax.plot(t, body[:, c], color="tab:green", lw=1.0, alpha=0.7, label="body")
            ax.plot(t, ref[:, c], "--", color="0.35", lw=1.3, label="reference")
            ax.plot(t, actual[:, c], color="tab:blue", lw=1.3, label="flown")
            lo, hi = ax.get_ylim()
            ax.fill_between(t, lo, hi, where=pen, color="tab:orange", alpha=0.15, lw=0,
                            label="pen down")  # fmt: skip
            ax.set_ylim(lo, hi)
            ax.set_title(f"{name} {_AXES[c]} [{unit}]", fontsize=TITLE_PT - 1)
            ax.tick_params(labelsize=TICK_PT)
            if r == 1:
                ax.set_xlabel("time [s]", fontsize=LABEL_PT)


def _board_panel(
    ax: Axes, flown: FlownWriting, input_strokes_xy_m: Sequence[FloatArray] | None
) -> FloatArray:
    """The paths on the board; returns every point drawn, (n, 2) in [m]."""
    drawn = []
    for i, stroke in enumerate(input_strokes_xy_m or ()):
        pts = np.asarray(stroke, dtype=np.float64)
        ax.plot(pts[:, 0], pts[:, 1], color="tab:green", lw=4.0, alpha=0.45,
                label="input" if i == 0 else None)  # fmt: skip
        drawn.append(pts)
    ref = flown.reference_m_enu[:, :2].copy()
    ref[~flown.pen_down] = np.nan
    ax.plot(ref[:, 0], ref[:, 1], ":", color="k", lw=1.3, label="planned")
    tip = tip_of(flown)[:, :2].copy()
    tip[~(flown.ink_width_m > 0.0)] = np.nan
    ax.plot(tip[:, 0], tip[:, 1], color="tab:red", lw=1.2, label="brush (flown)")
    ax.set_title("board: input, planned, flown", fontsize=TITLE_PT - 1)
    drawn += [ref, tip]
    points = np.concatenate(drawn)
    return points[np.isfinite(points).all(axis=1)]


def _ink_panels(axes: Sequence[Axes], ink: InkResult, metrics: FlightMetrics) -> FloatArray:
    """Written and target ink; returns the corners of the rasters, (2, 2) in [m]."""
    extent = ink.target.spec.extent_m()
    panels = (
        (ink.written.pixels, f"written ink (IoU {metrics.iou:.2f})"),
        (ink.target.pixels, "target ink (planned path, nominal width)"),
    )
    for ax, (pixels, title) in zip(axes, panels, strict=True):
        ax.imshow(pixels, origin="lower", extent=extent, cmap="Greys", interpolation="nearest")
        ax.set_title(title, fontsize=TITLE_PT - 1)
    return np.array([[extent[0], extent[2]], [extent[1], extent[3]]])


def _frame(axes: Sequence[Axes], points_m: FloatArray) -> None:
    """The same square window on every board panel around ``points_m``, with a free border
    (a stroke at the edge, like 永's top dot, stays whole)."""
    lo, hi = points_m.min(axis=0), points_m.max(axis=0)
    half = 0.5 * float(np.max(hi - lo)) * (1.0 + 2.0 * BOARD_MARGIN)
    centre = 0.5 * (lo + hi)
    for ax in axes:
        ax.set_xlim(centre[0] - half, centre[0] + half)
        ax.set_ylim(centre[1] - half, centre[1] + half)
        ax.set_aspect("equal")
        ax.tick_params(labelsize=TICK_PT)
        ax.set_xlabel("board x [m]", fontsize=LABEL_PT)
    axes[0].set_ylabel("board y [m]", fontsize=LABEL_PT)


def build_report(
    flown: FlownWriting,
    planned: TrajectorySamples,
    brush: BrushParams,
    metrics: FlightMetrics,
    ink: InkResult,
    *,
    input_strokes_xy_m: Sequence[FloatArray] | None = None,
    title: str = "",
) -> Figure:
    """The report figure of one vehicle's flight of ``planned`` (the writing point's reference,
    whose velocity is drawn) with ``brush`` (not yet saved)."""
    fig = report_figure(HEIGHT_IN)
    grid = fig.add_gridspec(3, 3, height_ratios=(1.0, 1.0, 1.6))
    _time_rows(fig, flown, planned, brush, grid)
    board = [fig.add_subplot(grid[2, c]) for c in range(3)]
    points = _board_panel(board[0], flown, input_strokes_xy_m)
    corners = _ink_panels(board[1:], ink, metrics)
    _frame(board, points if points.size else corners)
    legend_below(fig)
    pen = metrics.rmse_pen_down_m
    summary = (
        ("pen never down, " if pen is None else f"pen-down RMSE {pen * 1000:.1f} mm, ")
        + f"whole flight {metrics.rmse_m * 1000:.1f} mm, max {metrics.max_error_m * 1000:.1f} mm, "
        f"IoU {metrics.iou:.2f}, {metrics.sim_time_s:.1f} s simulated"
    )
    heading = f"{plain_heading(title)}\n{summary}" if title else summary
    fig.suptitle(heading, fontsize=TITLE_PT, parse_math=False)  # a title may hold a public label
    return fig

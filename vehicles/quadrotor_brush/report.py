"""The flight report figure (``report.png``): tracking against time and the writing on the board.

Rows: position x, y, z against time (Phang 2015 Fig. 12: the writing point, i.e. the brush axis at
the nominal lever, and the body, which leans away from it on purpose); velocity x, y, z of the
body (Fig. 13); the input
strokes, planned path and flown brush path on the board (Fig. 14), then the written ink beside the
target ink with their intersection over union (Guo 2024 section VII). Matplotlib's Agg backend
only, never pyplot, so it runs headless and in threads. The title is data (it may hold a label
from the public): drawn literally, never as mathtext (:func:`plain_title`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from numpy.typing import NDArray

from planner.samples import TrajectorySamples
from vehicles.kind import FlownWriting
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
                ax.plot(t, body[:, c], color="tab:green", lw=0.7, alpha=0.6, label="body")
            ax.plot(t, ref[:, c], "--", color="tab:gray", lw=1.0, label="reference")
            ax.plot(t, actual[:, c], color="tab:blue", lw=0.9, label="flown")
            lo, hi = ax.get_ylim()
            ax.fill_between(t, lo, hi, where=pen, color="tab:orange", alpha=0.12, lw=0)
            ax.set_ylim(lo, hi)
            ax.set_title(f"{name} {_AXES[c]} [{unit}]", fontsize=9)
            ax.tick_params(labelsize=7)
            if r == 1:
                ax.set_xlabel("t [s]", fontsize=8)
            if r == 0 and c == 0:
                ax.legend(fontsize=7, loc="best")


def _board_panel(
    fig: Figure,
    flown: FlownWriting,
    grid: object,
    input_strokes_xy_m: Sequence[FloatArray] | None,
) -> None:
    ax = fig.add_subplot(grid[2, 0])  # type: ignore[index]
    if input_strokes_xy_m:
        for i, stroke in enumerate(input_strokes_xy_m):
            pts = np.asarray(stroke, dtype=np.float64)
            ax.plot(pts[:, 0], pts[:, 1], color="tab:green", lw=2.5, alpha=0.45,
                    label="input" if i == 0 else None)  # fmt: skip
    ref = flown.reference_m_enu[:, :2].copy()
    ref[~flown.pen_down] = np.nan
    ax.plot(ref[:, 0], ref[:, 1], ":", color="k", lw=1.0, label="planned")
    tip = tip_of(flown)[:, :2].copy()
    tip[~(flown.ink_width_m > 0.0)] = np.nan
    ax.plot(tip[:, 0], tip[:, 1], color="tab:red", lw=0.8, label="brush (flown)")
    ax.set_aspect("equal")
    ax.set_title("board: input, planned, flown", fontsize=9)
    ax.tick_params(labelsize=7)
    ax.legend(fontsize=7, loc="best")


def _ink_panels(fig: Figure, ink: InkResult, metrics: FlightMetrics, grid: object) -> None:
    extent = ink.target.spec.extent_m()
    panels = (
        (ink.written.pixels, f"written ink (IoU {metrics.iou:.2f})"),
        (ink.target.pixels, "target ink (planned path, nominal width)"),
    )
    for c, (pixels, title) in enumerate(panels, start=1):
        ax = fig.add_subplot(grid[2, c])  # type: ignore[index]
        ax.imshow(pixels, origin="lower", extent=extent, cmap="Greys", interpolation="nearest")
        ax.set_title(title, fontsize=9)
        ax.tick_params(labelsize=7)


TITLE_MAX_CHARS = 160
"""Longest title drawn, in characters (before spelling): a label is data of any length."""


def plain_title(text: str) -> str:
    """``text`` as a title that is drawn literally: cut to ``TITLE_MAX_CHARS`` with an ellipsis,
    one line, and every character the default font lacks (CJK) or that is not printable
    (control codes, bidirectional overrides, line breaks) spelt as U+XXXX. The caller draws it
    with ``parse_math=False``, so ``$...$`` stays text rather than matplotlib mathtext."""
    if len(text) > TITLE_MAX_CHARS:
        text = text[: TITLE_MAX_CHARS - 3] + "..."
    return "".join(
        ch if ch.isprintable() and ord(ch) < 0x2000 else f"U+{ord(ch):04X}" for ch in text
    )


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
    fig = Figure(figsize=(15.0, 13.0), dpi=100)
    FigureCanvasAgg(fig)
    grid = fig.add_gridspec(3, 3, height_ratios=(1.0, 1.0, 1.7), hspace=0.35, wspace=0.25)
    _time_rows(fig, flown, planned, brush, grid)
    _board_panel(fig, flown, grid, input_strokes_xy_m)
    _ink_panels(fig, ink, metrics, grid)
    summary = (
        f"pen-down RMSE {metrics.rmse_pen_down_m * 1000:.1f} mm, "
        f"whole flight {metrics.rmse_m * 1000:.1f} mm, max {metrics.max_error_m * 1000:.1f} mm, "
        f"IoU {metrics.iou:.2f}, {metrics.sim_time_s:.1f} s simulated"
    )
    heading = f"{plain_title(title)}\n{summary}" if title else summary
    fig.suptitle(heading, fontsize=11, parse_math=False)  # a title may hold a public label
    return fig

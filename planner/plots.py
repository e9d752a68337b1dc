"""Figures of a planned trajectory (like Fig. 6-9 of the paper). Returns a Figure; no file I/O.

Uses matplotlib's object API with the Agg canvas (no pyplot, no display).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from planner.bspline import FloatArray
from planner.samples import BoolArray
from planner.trajectory import PlannedTrajectory

_AXIS_COLOURS = ("tab:red", "tab:green", "tab:blue")


def _shade_pen_down(ax: Axes, t: FloatArray, pen: BoolArray) -> None:
    steps = np.diff(np.concatenate([[0], pen.astype(np.int8), [0]]))
    for s, e in zip(np.flatnonzero(steps == 1), np.flatnonzero(steps == -1) - 1, strict=True):
        ax.axvspan(t[s], t[e], color="0.85", lw=0, zorder=0)


def _plane_view(
    ax: Axes,
    traj: PlannedTrajectory,
    strokes_board_m: Sequence[FloatArray] | None,
    p_board: FloatArray,
    pen: BoolArray,
) -> None:
    if strokes_board_m is not None:
        for k, stroke in enumerate(strokes_board_m):
            pts = np.asarray(stroke)
            ax.plot(
                pts[:, 0],
                pts[:, 1],
                ".",
                color="0.6",
                ms=3,
                label="input points" if k == 0 else None,
            )
    up = np.where(pen, np.nan, 1.0)[:, None] * p_board
    down = np.where(pen, 1.0, np.nan)[:, None] * p_board
    ax.plot(up[:, 0], up[:, 1], "--", color="tab:orange", lw=0.8, label="pen up")
    ax.plot(down[:, 0], down[:, 1], "-", color="tab:blue", lw=1.8, label="pen down")
    for k, tp in enumerate(traj.turning_points_board_m):
        ax.plot(
            tp[:, 0],
            tp[:, 1],
            "o",
            mfc="none",
            color="tab:red",
            ms=5,
            label="turning points" if k == 0 else None,
        )
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("board x [m]")
    ax.set_ylabel("board y [m]")
    ax.set_title("input, turning points and planned path")
    ax.legend(loc="best", fontsize="small")


def plot_trajectory(
    traj: PlannedTrajectory,
    strokes_board_m: Sequence[FloatArray] | None = None,
    *,
    rate_hz: float = 100.0,
) -> Figure:
    """Four panels: board view (input, turning points, path), height, speed, acceleration.

    Pen-down times are shaded grey; limits are drawn as dashed lines.
    """
    t = traj.sample_times(rate_hz)
    p, v, a, _ = traj.evaluate(t)
    pen = traj.pen_down(t)
    fig = Figure(figsize=(12.0, 8.0), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, 2)
    _plane_view(axes[0, 0], traj, strokes_board_m, traj.board.to_board(p), pen)

    ax = axes[0, 1]
    _shade_pen_down(ax, t, pen)
    ax.plot(t, traj.board.height_above_m(p), color="tab:blue")
    ax.axhline(traj.write_z_m - traj.board.surface_z_m, ls="--", color="0.3", lw=0.8)
    ax.set_ylabel("height above board [m]")
    ax.set_title("height (pen down shaded)")

    ax = axes[1, 0]
    _shade_pen_down(ax, t, pen)
    ax.plot(t, np.linalg.norm(v, axis=1), color="k", label="|v|")
    for i, name in enumerate("xyz"):
        ax.plot(t, v[:, i], color=_AXIS_COLOURS[i], lw=0.8, label=f"v_{name}")
    ax.axhline(traj.limits.v_max_mps, ls="--", color="k", lw=0.8, label="v_max")
    ax.set_ylabel("velocity [m/s]")
    ax.set_xlabel("t [s]")
    ax.legend(loc="upper right", fontsize="small", ncol=5)

    ax = axes[1, 1]
    _shade_pen_down(ax, t, pen)
    lower, upper = traj.feasibility.accel_lower_mps2, traj.feasibility.accel_upper_mps2
    for i, name in enumerate("xyz"):
        colour = _AXIS_COLOURS[i]
        ax.plot(t, a[:, i], color=colour, lw=1.0, label=f"a_{name}")
        ax.axhline(upper[i], ls="--", color=colour, lw=0.7)
        ax.axhline(lower[i], ls="--", color=colour, lw=0.7)
    ax.set_ylabel("acceleration [m/s^2]")
    ax.set_xlabel("t [s]")
    ax.legend(loc="upper right", fontsize="small", ncol=3)
    fig.suptitle(
        f"{traj.duration_s:.1f} s, fit error max {traj.feasibility.fit_error_max_m * 1e3:.1f} mm"
    )
    return fig

"""The job's report figure: target and written images, and position, force and width against
time (drawn only where a report is written)."""

from __future__ import annotations

from typing import Any

import numpy as np

from vehicles.hexarotor_sponge import metrics
from vehicles.kind import FlownWriting, WritingPlan, WritingScore


def report_figure(
    plan: WritingPlan, flown: FlownWriting, score: WritingScore, title: str, default_width_m: float
) -> Any:
    """A matplotlib figure (Agg) of one flown job."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(12, 7), layout="constrained")
    grid = fig.add_gridspec(3, 2, width_ratios=(1.0, 1.4))
    ax_img = fig.add_subplot(grid[:, 0])
    origin, shape = metrics.raster_frame(plan.strokes)
    target = metrics.target_image(plan.strokes, default_width_m, origin, shape)
    written = metrics.written_image(flown, plan.surface, origin, shape)
    rgb = np.ones((*shape, 3))
    rgb[target] = (0.75, 0.85, 1.0)
    rgb[written] = (0.1, 0.1, 0.1)
    rgb[target & written] = (0.1, 0.3, 0.8)
    extent = (origin[0], origin[0] + shape[1] * 1e-3, origin[1], origin[1] + shape[0] * 1e-3)
    ax_img.imshow(rgb, origin="lower", extent=extent)
    ax_img.set_title(f"target (light) and written (dark), IoU {score.iou or 0.0:.2f}")
    ax_img.set_xlabel("wall x [m]")
    ax_img.set_ylabel("wall y [m]")
    t = flown.t_s
    err = np.linalg.norm(flown.writing_point_m_enu - flown.reference_m_enu, axis=1)
    ax_err = fig.add_subplot(grid[0, 1])
    ax_err.plot(t, err * 100.0, lw=0.8)
    ax_err.set_ylabel("tip error [cm]")
    ax_err.set_title(f"EE RMSE {score.extra.get('rmse_ee_m', float('nan')) * 100:.2f} cm")
    ax_f = fig.add_subplot(grid[1, 1], sharex=ax_err)
    if plan.force_n is not None:
        ax_f.plot(t, plan.force_n, label="planned", lw=1.2)
    if flown.force_n is not None:
        ax_f.plot(t, flown.force_n, label="contact", lw=0.6)
    ax_f.set_ylabel("normal force [N]")
    ax_f.set_title(f"force RMSE {score.extra.get('force_rmse_n', float('nan')):.2f} N")
    ax_f.legend(loc="upper right")
    ax_w = fig.add_subplot(grid[2, 1], sharex=ax_err)
    if plan.width_m is not None:
        ax_w.plot(t, plan.width_m * 1e3, label="planned", lw=1.2)
    ax_w.plot(t, flown.ink_width_m * 1e3, label="ink", lw=0.6)
    ax_w.set_ylabel("line width [mm]")
    ax_w.set_xlabel("time [s]")
    ax_w.legend(loc="upper right")
    fig.suptitle(title)
    return fig

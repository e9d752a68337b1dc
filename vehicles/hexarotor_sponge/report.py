"""The job's report figure: target and written images, and tip error, force and width against
time (drawn only where a report is written). The title is data (a public label): drawn
literally (:func:`vehicles.picture.plain_heading`)."""

from __future__ import annotations

from typing import Any

import numpy as np

from vehicles import picture
from vehicles.hexarotor_sponge import metrics
from vehicles.kind import FlownWriting, WritingPlan, WritingScore
from vehicles.picture import LABEL_PT, TICK_PT, TITLE_PT, legend_below, plain_heading

HEIGHT_IN = 7.2
"""Height in [in] of the figure (1280 x 720 px at 100 dpi)."""


def report_figure(
    plan: WritingPlan, flown: FlownWriting, score: WritingScore, title: str, default_width_m: float
) -> Any:
    """A matplotlib figure (Agg) of one flown job."""
    fig = picture.report_figure(HEIGHT_IN)
    grid = fig.add_gridspec(3, 2, width_ratios=(1.0, 1.5))
    ax_img = fig.add_subplot(grid[:, 0])
    origin, shape = metrics.raster_frame(plan.strokes)
    target = metrics.target_image(plan.strokes, default_width_m, origin, shape)
    written = metrics.written_image(flown, plan.surface, origin, shape)
    rgb = np.ones((*shape, 3))
    rgb[target] = (0.75, 0.85, 1.0)
    rgb[written] = (0.1, 0.1, 0.1)
    rgb[target & written] = (0.1, 0.3, 0.8)
    extent = (origin[0], origin[0] + shape[1] * 1e-3, origin[1], origin[1] + shape[0] * 1e-3)
    ax_img.imshow(rgb, origin="lower", extent=extent, interpolation="nearest")
    ax_img.set_title(
        f"target (light), written (dark), both (blue): IoU {score.iou or 0.0:.2f}",
        fontsize=TITLE_PT - 1,
    )
    ax_img.set_xlabel("wall x [m]", fontsize=LABEL_PT)
    ax_img.set_ylabel("wall y [m]", fontsize=LABEL_PT)
    t = flown.t_s
    plan_t = plan.samples.t_s  # a live run has its own ticks; both start when writing does
    err = np.linalg.norm(flown.writing_point_m_enu - flown.reference_m_enu, axis=1)
    ax_err = fig.add_subplot(grid[0, 1])
    ax_err.plot(t, err * 100.0, lw=1.2, color="tab:blue")
    ax_err.set_ylabel("tip error [cm]", fontsize=LABEL_PT)
    rmse_cm = score.extra.get("rmse_ee_m", float("nan")) * 100
    ax_err.set_title(f"tip error: RMSE {rmse_cm:.2f} cm", fontsize=TITLE_PT - 1)
    ax_f = fig.add_subplot(grid[1, 1], sharex=ax_err)
    if plan.force_n is not None:
        ax_f.plot(plan_t, plan.force_n, label="planned", lw=2.0, color="tab:gray")
    if flown.force_n is not None:
        ax_f.plot(t, flown.force_n, label="measured", lw=1.0, color="tab:red")
    ax_f.set_ylabel("normal force [N]", fontsize=LABEL_PT)
    force_rmse_n = score.extra.get("force_rmse_n", float("nan"))
    ax_f.set_title(f"normal force: RMSE {force_rmse_n:.2f} N", fontsize=TITLE_PT - 1)
    ax_w = fig.add_subplot(grid[2, 1], sharex=ax_err)
    if plan.width_m is not None:
        ax_w.plot(plan_t, plan.width_m * 1e3, lw=2.0, color="tab:gray")
    ax_w.plot(t, flown.ink_width_m * 1e3, lw=1.0, color="tab:red")
    ax_w.set_ylabel("line width [mm]", fontsize=LABEL_PT)
    ax_w.set_title("line width", fontsize=TITLE_PT - 1)
    ax_w.set_xlabel("time [s]", fontsize=LABEL_PT)
    for ax in (ax_img, ax_err, ax_f, ax_w):
        ax.tick_params(labelsize=TICK_PT)
    for ax in (ax_err, ax_f):
        ax.tick_params(labelbottom=False)
    legend_below(fig)
    fig.suptitle(plain_heading(title), fontsize=TITLE_PT, parse_math=False)
    return fig

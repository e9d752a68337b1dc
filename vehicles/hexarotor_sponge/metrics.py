"""Metrics of one flown job as the paper's Table I: end-effector and base position RMSE, normal
force RMSE, IoU of target and written images drawn with their line widths; beside this tracking,
fidelity to the letter: how far the inked path and the plan's pen-down path lie from the target
strokes, and the IoU of the plan flown perfectly."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from sim.ink import iou as ink_iou
from vehicles.hexarotor_sponge.fidelity import to_strokes_figures
from vehicles.hexarotor_sponge.params import HexarotorParams
from vehicles.hexarotor_sponge.world import facing_rotation
from vehicles.kind import FlownWriting, StrokeInput, WritingPlan, WritingScore
from vehicles.surface import Surface

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

PIXEL_M = 1e-3
"""Raster pixel in [m]."""


def _rms(values: FloatArray) -> float:
    return float(np.sqrt(np.mean(values**2))) if values.size else float("nan")


def reference_base_m_enu(plan: WritingPlan, params: HexarotorParams) -> FloatArray:
    """(N, 3) body position in [m] that puts the tip on the plan at the planned force."""
    rot = facing_rotation(plan.surface)
    force = np.zeros(plan.samples.t_s.shape) if plan.force_n is None else plan.force_n
    squeeze = np.array([params.compression_m(float(f)) for f in force])
    nominal = plan.samples.position_m_enu - np.outer(squeeze, plan.surface.normal_enu)
    return np.asarray(nominal - rot @ np.asarray(params.tip_m_body))


def stamp(
    points_m: FloatArray, widths_m: FloatArray, origin_m: FloatArray, shape: tuple[int, int]
) -> BoolArray:
    """Raster (rows y, cols x) of discs of diameter ``widths_m`` at surface points (n, 2)."""
    image = np.zeros(shape, dtype=bool)
    for (x, y), w in zip(points_m, widths_m, strict=True):
        r = 0.5 * float(w) / PIXEL_M
        if r <= 0.0:
            continue
        cx, cy = (x - origin_m[0]) / PIXEL_M, (y - origin_m[1]) / PIXEL_M
        x0, x1 = max(int(cx - r), 0), min(int(cx + r) + 2, shape[1])
        y0, y1 = max(int(cy - r), 0), min(int(cy + r) + 2, shape[0])
        if x0 >= x1 or y0 >= y1:
            continue
        yy, xx = np.mgrid[y0:y1, x0:x1]
        image[y0:y1, x0:x1] |= (xx + 0.5 - cx) ** 2 + (yy + 0.5 - cy) ** 2 <= r * r
    return image


def densify(
    points_m: FloatArray, widths_m: FloatArray, joined: BoolArray
) -> tuple[FloatArray, FloatArray]:
    """Points and widths every half pixel along consecutive pairs where ``joined[i]`` links
    point i to i+1."""
    out_p, out_w = [points_m], [widths_m]
    for i in np.flatnonzero(joined):
        gap = float(np.linalg.norm(points_m[i + 1] - points_m[i]))
        k = int(gap / (0.5 * PIXEL_M))
        if k < 1:
            continue
        s = np.linspace(0.0, 1.0, k + 2)[1:-1, None]
        out_p.append(points_m[i] + s * (points_m[i + 1] - points_m[i]))
        out_w.append(widths_m[i] + s[:, 0] * (widths_m[i + 1] - widths_m[i]))
    return np.vstack(out_p), np.concatenate(out_w)


def target_image(
    strokes: Sequence[StrokeInput],
    default_width_m: float,
    origin: FloatArray,
    shape: tuple[int, int],
) -> BoolArray:
    """The target letter drawn with its wanted widths."""
    pts, ws = [], []
    for s in strokes:
        w = np.full(s.xy_m.shape[0], default_width_m) if s.width_m is None else s.width_m
        joined = np.ones(s.xy_m.shape[0] - 1, dtype=bool)
        p, wd = densify(s.xy_m, np.asarray(w, dtype=np.float64), joined)
        pts.append(p)
        ws.append(wd)
    return stamp(np.vstack(pts), np.concatenate(ws), origin, shape)


def written_image(
    flown: FlownWriting, surface: Surface, origin: FloatArray, shape: tuple[int, int]
) -> BoolArray:
    """What the sponge laid on the wall."""
    xy = surface.to_surface(flown.writing_point_m_enu)
    inked = flown.ink_width_m > 0.0
    p, w = densify(xy, flown.ink_width_m, inked[:-1] & inked[1:])
    return stamp(p, w, origin, shape)


def raster_frame(strokes: Sequence[StrokeInput]) -> tuple[FloatArray, tuple[int, int]]:
    """Origin (x, y) in [m] and shape of a raster holding the strokes with 5 cm to spare."""
    allpts = np.vstack([s.xy_m for s in strokes])
    lo = allpts.min(axis=0) - 0.05
    hi = allpts.max(axis=0) + 0.05
    size = np.ceil((hi - lo) / PIXEL_M).astype(int)
    return lo, (int(size[1]), int(size[0]))


def iou(plan: WritingPlan, flown: FlownWriting, default_width_m: float) -> float:
    """Intersection over union of target and written images (:func:`sim.ink.iou`, the one
    rule of every kind: nothing written scores 0)."""
    origin, shape = raster_frame(plan.strokes)
    target = target_image(plan.strokes, default_width_m, origin, shape)
    return ink_iou(written_image(flown, plan.surface, origin, shape), target)


def as_flown(plan: WritingPlan) -> FlownWriting:
    """The plan flown perfectly: the tip on its reference, the planned width where the pen is
    down."""
    down = plan.samples.pen_down
    width = np.zeros(down.shape) if plan.width_m is None else np.where(down, plan.width_m, 0.0)
    position = plan.samples.position_m_enu
    return FlownWriting(plan.samples.t_s, position, position, down, width)


def plan_fidelity(plan: WritingPlan, default_width_m: float) -> dict[str, float]:
    """The plan's own fidelity to its letter: ``plan_iou`` (flown perfectly) and the distance of
    its pen-down path from the strokes, ``plan_rmse_to_strokes_m``, ``plan_max_to_strokes_m``."""
    xy = plan.surface.to_surface(plan.samples.position_m_enu[plan.samples.pen_down])
    figures = to_strokes_figures(xy, plan.strokes)
    return {
        "plan_iou": iou(plan, as_flown(plan), default_width_m),
        **{f"plan_{name}": value for name, value in figures.items()},
    }


def score_writing(
    plan: WritingPlan, flown: FlownWriting, params: HexarotorParams, default_width_m: float
) -> WritingScore:
    """Table I's figures of one run (position RMSEs and force RMSE over the pen-down ticks),
    and the inked path's distance from the target strokes (``rmse_to_strokes_m``,
    ``max_to_strokes_m``) beside the plan's (:func:`plan_fidelity`). ``max_error_m`` is the
    largest tracking error while writing (pen down): before and after, the vehicle hovers off
    the wall and its offset from the first waypoint says nothing of the letter; a run whose pen
    never came down measured no writing: ``rmse_pen_down_m`` None, ``max_error_m`` the largest
    error of the whole run, and only the figures that were measured (finite) in ``extra``."""
    down = flown.pen_down
    err = np.linalg.norm(flown.writing_point_m_enu - flown.reference_m_enu, axis=1)
    inked = flown.writing_point_m_enu[flown.ink_width_m > 0.0]
    extra: dict[str, float] = {
        "rmse_ee_m": _rms(err[down]),
        **to_strokes_figures(plan.surface.to_surface(inked), plan.strokes),
        **plan_fidelity(plan, default_width_m),
    }
    if flown.base_m_enu is not None:
        base_err = flown.base_m_enu - reference_base_m_enu(plan, params)
        extra["rmse_base_m"] = _rms(np.linalg.norm(base_err, axis=1)[down])
    if flown.force_n is not None and plan.force_n is not None:
        extra["force_rmse_n"] = _rms((flown.force_n - plan.force_n)[down])
    if plan.width_m is not None:
        extra["width_rmse_m"] = _rms((flown.ink_width_m - plan.width_m)[down])
    return WritingScore(
        rmse_pen_down_m=extra["rmse_ee_m"] if down.any() else None,
        rmse_m=_rms(err),
        max_error_m=float(err[down].max() if down.any() else err.max(initial=0.0)),
        iou=iou(plan, flown, default_width_m),
        extra={name: value for name, value in extra.items() if np.isfinite(value)},
    )

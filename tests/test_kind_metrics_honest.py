"""Each kind's score claims only what was measured (issue 34), on known answers: a straight line
written perfectly but stopped at 30 % scores IoU about 0.3 against the whole line (not 1.0
against the part flown), and a run whose pen never came down has no pen-down figures, IoU 0, and
figures that survive the wire (a NaN is null in JSON and broke the ``done`` report)."""

from __future__ import annotations

from dataclasses import replace

import msgspec
import numpy as np
import pytest

from bus.messages import JobMetrics
from planner.samples import TrajectorySamples
from vehicles.hexarotor_sponge.kind import KIND as WALL
from vehicles.kind import FlownWriting, StrokeInput, WritingPlan, WritingScore
from vehicles.omni_wheel.floor_plan import DEFAULT_SETTINGS
from vehicles.omni_wheel.kind import KIND as GROUND
from vehicles.surface import Surface

WALL_SURFACE = Surface.of("vertical", (0.0, 3.0, 2.0), 0.0)
FLOOR = Surface.of("floor", (3.0, 1.0, 0.0), 0.0)
WIDTH_M = 10e-3


def _line(surface: Surface, length_m: float) -> WritingPlan:
    """A straight line along the surface's x, sampled every 1 mm, all pen down."""
    x = np.linspace(-length_m / 2, length_m / 2, round(length_m * 1e3) + 1, dtype=np.float64)
    xy = np.column_stack([x, np.zeros_like(x)])
    pos = surface.to_world(xy, 0.0)
    t = np.asarray(np.arange(x.size) * 0.01, dtype=np.float64)
    samples = TrajectorySamples(
        t, pos, np.zeros_like(pos), np.zeros_like(pos), np.ones(x.size, bool)
    )
    stroke = StrokeInput(xy[[0, -1]], np.full(2, WIDTH_M))
    force = np.full(x.size, 2.0)
    return WritingPlan(samples, (stroke,), surface, force_n=force, width_m=np.full(x.size, WIDTH_M))


def _perfect(plan: WritingPlan, width_m: float, upto: float = 1.0) -> FlownWriting:
    """``plan`` flown exactly to ``upto`` of its samples, inking ``width_m``."""
    n = round(upto * plan.samples.t_s.size)
    pos = plan.samples.position_m_enu[:n]
    return FlownWriting(
        t_s=plan.samples.t_s[:n],
        reference_m_enu=pos,
        writing_point_m_enu=pos,
        pen_down=plan.samples.pen_down[:n],
        ink_width_m=np.full(n, width_m),
    )


def _lifted(flown: FlownWriting) -> FlownWriting:
    """``flown`` with the pen never down and no ink."""
    none = np.zeros_like(flown.pen_down)
    return replace(flown, pen_down=none, ink_width_m=np.zeros_like(flown.ink_width_m))


def _on_the_wire(score: WritingScore) -> JobMetrics:
    metrics = JobMetrics(
        rmse_pen_down_m=score.rmse_pen_down_m,
        rmse_m=score.rmse_m,
        max_error_m=score.max_error_m,
        iou=score.iou,
        duration_s=1.0,
        extra=dict(score.extra),
    )
    return msgspec.json.decode(msgspec.json.encode(metrics), type=JobMetrics)


def test_a_floor_line_stopped_at_30_percent_scores_against_the_whole_line() -> None:
    plan = _line(FLOOR, 1.0)
    whole = GROUND.score(plan, _perfect(plan, DEFAULT_SETTINGS.marker_width_m), DEFAULT_SETTINGS)
    part = GROUND.score(
        plan, _perfect(plan, DEFAULT_SETTINGS.marker_width_m, 0.3), DEFAULT_SETTINGS
    )
    assert whole.iou == pytest.approx(1.0, abs=0.02)
    assert part.iou == pytest.approx(0.3, abs=0.05)  # today: 1.0, the part against itself
    assert part.rmse_pen_down_m == pytest.approx(0.0, abs=1e-12)


def test_a_floor_run_with_the_pen_never_down_claims_no_pen_down_figure() -> None:
    plan = _line(FLOOR, 1.0)
    score = GROUND.score(
        plan, _lifted(_perfect(plan, DEFAULT_SETTINGS.marker_width_m)), DEFAULT_SETTINGS
    )
    assert score.rmse_pen_down_m is None  # today: 0.0
    assert score.iou == 0.0 and "max_error_pen_down_m" not in score.extra
    assert _on_the_wire(score).rmse_pen_down_m is None


@pytest.mark.parametrize("upto", [1.0, 0.3])
def test_a_wall_line_scores_against_the_whole_line(upto: float) -> None:
    plan = _line(WALL_SURFACE, 0.2)
    score = WALL.score(plan, _perfect(plan, WIDTH_M, upto), None)
    assert score.iou == pytest.approx(upto, abs=0.05)


def test_a_wall_run_with_the_pen_never_down_survives_the_wire() -> None:
    plan = _line(WALL_SURFACE, 0.2)
    score = WALL.score(plan, _lifted(_perfect(plan, WIDTH_M)), None)
    assert score.rmse_pen_down_m is None  # today: NaN, null in JSON, undecodable
    assert score.iou == 0.0
    assert all(np.isfinite(value) for value in score.extra.values()), score.extra
    assert "rmse_ee_m" not in score.extra and np.isfinite(score.max_error_m)
    wire = _on_the_wire(score)
    assert wire.rmse_pen_down_m is None and wire.extra == dict(score.extra)

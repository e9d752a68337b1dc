"""The closed loop in batch: a plan flown, tick by tick, through the one loop of ``loop.py``."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from vehicles.hexarotor_sponge.controller import Reference
from vehicles.hexarotor_sponge.fly_settings import FlySettings
from vehicles.hexarotor_sponge.loop import WallLoop
from vehicles.kind import FlownWriting, WritingPlan

FloatArray = NDArray[np.float64]


def reference_at(plan: WritingPlan, k: int) -> Reference:
    """Sample ``k`` of the plan as a controller reference."""
    s = plan.samples
    force = 0.0 if plan.force_n is None else float(plan.force_n[k])
    return Reference(s.position_m_enu[k], s.velocity_mps_enu[k], s.acceleration_mps2_enu[k], force)


def fly_plan(plan: WritingPlan, settings: FlySettings, *, seed: int = 0) -> FlownWriting:
    """Fly ``plan`` to its end; one row per control tick of the writing."""
    loop = WallLoop(plan.samples.position_m_enu[0], plan.surface, settings, seed=seed)
    start = reference_at(plan, 0)
    # Hover at rest on the first point: the plan's first sample may already accelerate (towards
    # the wall), and feeding that forward for the whole settle pushed the vehicle 9.7 mm off the
    # point and wound the position integral up (the 9.6 mm ``max_error_m`` of every run, and
    # 3 mm short of the wall at the first pen-down).
    hold = Reference(start.position_m_enu, np.zeros(3), np.zeros(3), 0.0)
    for _ in range(round(settings.settle_s / loop.dt_s)):
        loop.track(hold)
    n = plan.samples.t_s.shape[0]
    tip, base, force, f_hat, thrust = (
        np.zeros((n, 3)),
        np.zeros((n, 3)),
        np.zeros(n),
        np.zeros(n),
        np.zeros((n, 6)),
    )
    for k in range(n):
        out = loop.track(reference_at(plan, k))
        truth = loop.truth()
        tip[k], base[k], force[k] = truth.tip_m_enu, truth.base_m_enu, truth.contact_force_n
        f_hat[k], thrust[k] = out.force_estimate_n, out.allocation.thrust_n
    return FlownWriting(
        t_s=plan.samples.t_s.copy(),
        reference_m_enu=plan.samples.position_m_enu.copy(),
        writing_point_m_enu=tip,
        pen_down=plan.samples.pen_down.copy(),
        ink_width_m=settings.params.pen.width_m(force),
        base_m_enu=base,
        force_n=force,
        extra={"force_estimate_n": f_hat, "thrust_n": thrust},
    )

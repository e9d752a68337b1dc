"""The closed loop in batch: a plan flown in the MuJoCo world under the hybrid controller."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from vehicles.hexarotor_sponge.controller import HybridController, Reference
from vehicles.hexarotor_sponge.params import HexarotorParams
from vehicles.hexarotor_sponge.world import WallWorld, WorldNoise, facing_rotation
from vehicles.kind import FlownWriting, WritingPlan

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class FlySettings:
    """How a plan is flown in simulation."""

    params: HexarotorParams = field(default_factory=HexarotorParams)
    """The vehicle."""
    noise: WorldNoise = field(default_factory=WorldNoise)
    """Wind and sensor noise."""
    contact_model: bool = True
    """False: the paper's control baseline (no contact wrench model in the controller)."""
    settle_s: float = 1.0
    """Hover at the first reference point before writing starts, in [s]."""
    control_dt_s: float = 0.01
    """Control period in [s]."""


def reference_at(plan: WritingPlan, k: int) -> Reference:
    """Sample ``k`` of the plan as a controller reference."""
    s = plan.samples
    force = 0.0 if plan.force_n is None else float(plan.force_n[k])
    return Reference(s.position_m_enu[k], s.velocity_mps_enu[k], s.acceleration_mps2_enu[k], force)


def start_base(plan: WritingPlan, params: HexarotorParams) -> FloatArray:
    """Body position in [m] that puts the nominal tip on the plan's first point."""
    rot = facing_rotation(plan.surface)
    return np.asarray(plan.samples.position_m_enu[0] - rot @ np.asarray(params.tip_m_body))


def fly_plan(plan: WritingPlan, settings: FlySettings, *, seed: int = 0) -> FlownWriting:
    """Fly ``plan`` to its end; one row per control tick of the writing."""
    params = settings.params
    world = WallWorld(
        params,
        plan.surface,
        base_m_enu=start_base(plan, params),
        noise=settings.noise,
        seed=seed,
        control_dt_s=settings.control_dt_s,
    )
    ctrl = HybridController(
        params, plan.surface, dt_s=world.control_dt_s, contact_model=settings.contact_model
    )
    hold = reference_at(plan, 0)
    for _ in range(round(settings.settle_s / world.control_dt_s)):
        world.step(ctrl.update(world.measure(), hold).allocation.thrust_n)
    n = plan.samples.t_s.shape[0]
    tip, base, force, f_hat, thrust = (
        np.zeros((n, 3)),
        np.zeros((n, 3)),
        np.zeros(n),
        np.zeros(n),
        np.zeros((n, 6)),
    )
    for k in range(n):
        out = ctrl.update(world.measure(), reference_at(plan, k))
        world.step(out.allocation.thrust_n)
        truth = world.truth()
        tip[k], base[k], force[k] = truth.tip_m_enu, truth.base_m_enu, truth.contact_force_n
        f_hat[k], thrust[k] = out.force_estimate_n, out.allocation.thrust_n
    return FlownWriting(
        t_s=plan.samples.t_s.copy(),
        reference_m_enu=plan.samples.position_m_enu.copy(),
        writing_point_m_enu=tip,
        pen_down=plan.samples.pen_down.copy(),
        ink_width_m=params.pen.width_m(force),
        base_m_enu=base,
        force_n=force,
        extra={"force_estimate_n": f_hat, "thrust_n": thrust},
    )

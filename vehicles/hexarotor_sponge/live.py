"""A live simulated hexarotor for the agent's ``sim`` backend: the MuJoCo world under the hybrid
controller, one control period per ``step``."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from vehicles.hexarotor_sponge.controller import HybridController, Reference
from vehicles.hexarotor_sponge.flight import FlySettings
from vehicles.hexarotor_sponge.world import WallWorld, facing_rotation
from vehicles.surface import Surface, Vec3

FloatArray = NDArray[np.float64]


class LiveReferenceLike(Protocol):
    """What the agent gives each tick (``vehicles.kind.LiveReference`` has these fields)."""

    @property
    def position_m_enu(self) -> Vec3: ...
    @property
    def velocity_mps_enu(self) -> Vec3: ...
    @property
    def acceleration_mps2_enu(self) -> Vec3: ...
    @property
    def pen_down(self) -> bool: ...
    @property
    def force_n(self) -> float | None: ...


@dataclass(frozen=True)
class WallLiveState:
    """The vehicle after a tick (fields of ``vehicles.kind.LiveState``)."""

    position_m_enu: Vec3
    """Writing point (pen tip) in [m], ENU: the reference point of this kind."""
    velocity_mps_enu: Vec3
    """Body velocity in [m/s], ENU."""
    pen_tip_m_enu: Vec3
    """Pen tip in [m], ENU."""
    pen_contact: bool
    """The sponge touches the wall."""
    pen_width_m: float
    """Width in [m] of the ink laid now."""
    force_n: float | None
    """Normal contact force in [N]."""


def _vec(v: FloatArray) -> Vec3:
    return (float(v[0]), float(v[1]), float(v[2]))


class WallVehicle:
    """World and controller in one closed loop, stepped by the agent."""

    def __init__(
        self, start_m_enu: FloatArray, surface: Surface, settings: FlySettings, *, seed: int = 0
    ) -> None:
        params = settings.params
        base = start_m_enu - facing_rotation(surface) @ np.asarray(params.tip_m_body)
        self.world = WallWorld(
            params,
            surface,
            base_m_enu=base,
            noise=settings.noise,
            seed=seed,
            control_dt_s=settings.control_dt_s,
        )
        self.controller = HybridController(
            params, surface, dt_s=self.world.control_dt_s, contact_model=settings.contact_model
        )
        self.dt_s = self.world.control_dt_s
        self.default_force_n = float(params.pen.force_n(np.array([9e-3]))[0])
        self.pen = params.pen

    def step(self, reference: LiveReferenceLike) -> None:
        """Track ``reference`` for one tick (pen down without a force: the 9 mm line's force)."""
        force = reference.force_n
        if force is None:
            force = self.default_force_n if reference.pen_down else 0.0
        ref = Reference(
            np.asarray(reference.position_m_enu, dtype=np.float64),
            np.asarray(reference.velocity_mps_enu, dtype=np.float64),
            np.asarray(reference.acceleration_mps2_enu, dtype=np.float64),
            float(force),
        )
        out = self.controller.update(self.world.measure(), ref)
        self.world.step(out.allocation.thrust_n)

    def state(self) -> WallLiveState:
        """True state now."""
        truth = self.world.truth()
        width = float(self.pen.width_m(np.array([truth.contact_force_n]))[0])
        return WallLiveState(
            position_m_enu=_vec(truth.tip_m_enu),
            velocity_mps_enu=_vec(self.world.data.qvel[0:3]),
            pen_tip_m_enu=_vec(truth.tip_m_enu),
            pen_contact=truth.contact_force_n > 0.0,
            pen_width_m=width,
            force_n=truth.contact_force_n,
        )

"""A live simulated hexarotor for the agent's ``sim`` backend: the one closed loop of ``loop.py``,
one control period per ``step`` of the agent's reference."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from vehicles.attitude import quaternion_of_wxyz
from vehicles.hexarotor_sponge.controller import Reference
from vehicles.hexarotor_sponge.fly_settings import FlySettings
from vehicles.hexarotor_sponge.loop import WallLoop
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
    attitude_xyzw_enu: tuple[float, float, float, float]
    """The body's attitude: quaternion (x, y, z, w), body FLU -> world ENU."""


def _vec(v: FloatArray) -> Vec3:
    return (float(v[0]), float(v[1]), float(v[2]))


class WallVehicle:
    """The closed loop stepped by the agent; a pen-down reference without a force asks for the
    force of a ``default_width_m`` line."""

    def __init__(
        self,
        start_m_enu: FloatArray,
        surface: Surface,
        settings: FlySettings,
        *,
        default_width_m: float,
        seed: int = 0,
    ) -> None:
        self.loop = WallLoop(start_m_enu, surface, settings, seed=seed)
        self.dt_s = self.loop.dt_s
        self.pen = settings.params.pen
        self.default_force_n = float(self.pen.force_n(np.array([default_width_m]))[0])

    def step(self, reference: LiveReferenceLike) -> None:
        """Track ``reference`` for one tick."""
        force = reference.force_n
        if force is None:
            force = self.default_force_n if reference.pen_down else 0.0
        self.loop.track(
            Reference(
                np.asarray(reference.position_m_enu, dtype=np.float64),
                np.asarray(reference.velocity_mps_enu, dtype=np.float64),
                np.asarray(reference.acceleration_mps2_enu, dtype=np.float64),
                float(force),
            )
        )

    def state(self) -> WallLiveState:
        """True state now."""
        truth = self.loop.truth()
        width = float(self.pen.width_m(np.array([truth.contact_force_n]))[0])
        return WallLiveState(
            position_m_enu=_vec(truth.tip_m_enu),
            velocity_mps_enu=_vec(self.loop.world.data.qvel[0:3]),
            pen_tip_m_enu=_vec(truth.tip_m_enu),
            pen_contact=truth.contact_force_n > 0.0,
            pen_width_m=width,
            force_n=truth.contact_force_n,
            attitude_xyzw_enu=quaternion_of_wxyz(truth.attitude_wxyz_enu),
        )

"""The one closed loop of the wall writer: the MuJoCo world under the hybrid controller, one
control period per :meth:`WallLoop.track`. The batch flight (``flight.fly_plan``) and the agent's
live simulated vehicle (``live.WallVehicle``) both step it, so they fly alike
(tests/test_wall_kind.py holds them equal)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from vehicles.hexarotor_sponge.controller import ControlOutput, HybridController, Reference
from vehicles.hexarotor_sponge.fly_settings import FlySettings
from vehicles.hexarotor_sponge.params import HexarotorParams
from vehicles.hexarotor_sponge.world import Truth, WallWorld, facing_rotation
from vehicles.surface import Surface

FloatArray = NDArray[np.float64]


def base_for_tip(tip_m_enu: FloatArray, surface: Surface, params: HexarotorParams) -> FloatArray:
    """Body position in [m], ENU, that puts the nominal pen tip at ``tip_m_enu`` facing
    ``surface``."""
    rot = facing_rotation(surface)
    return np.asarray(tip_m_enu - rot @ np.asarray(params.tip_m_body), dtype=np.float64)


class WallLoop:
    """World and controller, the pen tip starting at ``tip_m_enu`` in front of ``surface``."""

    def __init__(
        self, tip_m_enu: FloatArray, surface: Surface, settings: FlySettings, *, seed: int = 0
    ) -> None:
        params = settings.params
        self.world = WallWorld(
            params,
            surface,
            base_m_enu=base_for_tip(tip_m_enu, surface, params),
            noise=settings.noise,
            seed=seed,
            control_dt_s=settings.control_dt_s,
        )
        self.controller = HybridController(
            params,
            surface,
            dt_s=self.world.control_dt_s,
            contact_model=settings.contact_model,
            disturbance_observer=settings.disturbance_observer,
        )
        self.dt_s = self.world.control_dt_s
        """Control period in [s]."""

    def track(self, ref: Reference) -> ControlOutput:
        """One control period towards ``ref``: measure, command, step the world."""
        out = self.controller.update(self.world.measure(), ref)
        self.world.step(out.allocation.thrust_n)
        return out

    def truth(self) -> Truth:
        """True base, tip and contact force now."""
        return self.world.truth()

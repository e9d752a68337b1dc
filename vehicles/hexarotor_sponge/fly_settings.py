"""How a plan is flown in the simulated world: the vehicle, wind and sensor noise, the control
period (plain data). Kept apart from the MuJoCo world (``world``) and the loop (``loop``) that use
them, so that the kind's settings, and planning, load no MuJoCo.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from vehicles.hexarotor_sponge.params import HexarotorParams


@dataclass(frozen=True)
class WorldNoise:
    """Disturbances and sensor imperfections of one run."""

    wind_mps: float = 1.0
    """Mean wind speed in [m/s], blowing along the wall (the surface's x axis)."""
    gust_mps: float = 0.3
    """Standard deviation in [m/s] of the wind's turbulence (Ornstein-Uhlenbeck, 1 s)."""
    drag_area_m2: float = 0.15
    """Drag coefficient times frontal area of the vehicle in [m^2]."""
    mocap_position_m: float = 1.0e-3
    """Motion-capture position noise, standard deviation in [m]."""
    mocap_attitude_rad: float = 3.0e-3
    """Motion-capture attitude noise, standard deviation in [rad] per axis."""
    mocap_velocity_mps: float = 5.0e-3
    """Velocity estimate noise, standard deviation in [m/s]."""
    mocap_latency_s: float = 0.01
    """Motion-capture latency in [s]."""
    ft_force_n: float = 0.05
    """F/T sensor force noise, standard deviation in [N]."""
    ft_torque_nm: float = 5.0e-3
    """F/T sensor torque noise, standard deviation in [N m]."""


CALM = WorldNoise(0.0, 0.0, 0.15, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
"""No wind, perfect sensors (for tests that isolate one effect)."""


@dataclass(frozen=True)
class FlySettings:
    """How a plan is flown in simulation."""

    params: HexarotorParams = field(default_factory=HexarotorParams)
    """The vehicle."""
    noise: WorldNoise = field(default_factory=WorldNoise)
    """Wind and sensor noise."""
    contact_model: bool = True
    """False: the paper's control baseline (no contact wrench model in the controller)."""
    disturbance_observer: bool = True
    """Cancel the wind with ``disturbance_observer`` in the motion control (our extension, in
    both the contact-aware loop and the control baseline); False: the paper's eq. 12, whose only
    answer to the wind is the position integral."""
    settle_s: float = 1.0
    """Hover at the first reference point before writing starts, in [s]."""
    control_dt_s: float = 0.01
    """Control period in [s]."""

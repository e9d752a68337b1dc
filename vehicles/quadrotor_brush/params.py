"""Typed parameters of the brush quadrotor's simulated world: vehicle, brush, board (wind and
motion capture: :mod:`sim.params`).

Defaults describe the Airshow quadrotor of Phang et al. 2015 (section 2): about 1 kg, 10 inch
propellers, an inner attitude loop of about 25 rad/s, thrust-to-weight about 2, a calligraphy brush
on a linear bearing below the body, a Vicon-like motion-capture system.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from sim.errors import SimError
from sim.params import MocapParams, Vec3, WindParams, non_negative, positive


@dataclass(frozen=True)
class QuadrotorParams:
    """Translational dynamics, inner loop and actuators of one quadrotor."""

    mass_kg: float = 1.0
    """Take-off mass in [kg]."""
    gravity_mps2: float = 9.81
    """Gravitational acceleration in [m/s^2]."""
    thrust_to_weight: float = 2.0
    """Maximum collective rotor thrust divided by weight (out of ground effect)."""
    attitude_natural_freq_radps: float = 25.0
    """Natural frequency of the closed inner attitude loop in [rad/s] (second order)."""
    attitude_damping: float = 0.7
    """Damping ratio of the closed inner attitude loop."""
    max_tilt_rad: float = 0.5
    """The inner loop clamps roll and pitch commands to this magnitude in [rad]."""
    motor_time_constant_s: float = 0.02
    """First-order lag from throttle command to collective thrust in [s]."""
    throttle_per_mps2: float = 0.0334
    """Plant throttle gain: throttle units per [m/s^2] of specific collective thrust (eq. 2)."""
    drag_n_per_mps: Vec3 = (0.35, 0.35, 0.25)
    """Linear rotor drag per world axis in [N/(m/s)] of air-relative velocity."""
    rotor_radius_m: float = 0.127
    """Propeller radius in [m] (10 inch propellers), for ground effect."""
    rotor_height_m: float = 0.0
    """Height of the rotor plane above the vehicle reference point in [m]."""

    def __post_init__(self) -> None:
        for name in (
            "mass_kg",
            "gravity_mps2",
            "thrust_to_weight",
            "attitude_natural_freq_radps",
            "attitude_damping",
            "max_tilt_rad",
            "motor_time_constant_s",
            "throttle_per_mps2",
            "rotor_radius_m",
        ):
            positive(name, getattr(self, name))
        for value in self.drag_n_per_mps:
            non_negative("drag_n_per_mps", value)
        if self.thrust_to_weight <= 1.0:
            raise SimError("must exceed 1 to hover", field="thrust_to_weight")

    @property
    def max_specific_thrust_mps2(self) -> float:
        """Largest collective thrust per unit mass in [m/s^2]."""
        return self.thrust_to_weight * self.gravity_mps2


@dataclass(frozen=True)
class BrushParams:
    """A brush on a linear bearing, hanging along the body -z axis below the reference point."""

    length_m: float = 0.35
    """Reference point to brush tip in [m] with the brush fully extended (hanging free)."""
    travel_m: float = 0.05
    """Free travel of the bearing in [m]; beyond it the brush is bottomed out."""
    nominal_press_m: float = 0.015
    """Press (how far the shaft slid up the bearing) in [m] that gives the nominal width."""
    nominal_width_m: float = 0.02
    """Stroke width in [m] at the nominal press."""
    tip_width_m: float = 0.006
    """Stroke width in [m] when the tip just touches (press -> 0)."""

    def __post_init__(self) -> None:
        for name in ("length_m", "travel_m", "nominal_press_m", "nominal_width_m", "tip_width_m"):
            positive(name, getattr(self, name))
        if self.nominal_press_m >= self.travel_m:
            raise SimError("must be smaller than travel_m", field="nominal_press_m")
        if self.tip_width_m > self.nominal_width_m:
            raise SimError("must not exceed nominal_width_m", field="tip_width_m")

    @property
    def write_height_m(self) -> float:
        """Reference-point height above the board in [m] that gives the nominal press, level."""
        return self.length_m - self.nominal_press_m

    @property
    def width_per_press(self) -> float:
        """Growth of the stroke width with press, [m of width per m of press]."""
        return (self.nominal_width_m - self.tip_width_m) / self.nominal_press_m


@dataclass(frozen=True)
class WorldParams:
    """Everything the world needs besides the vehicles' initial positions and the seed."""

    quadrotor: QuadrotorParams = field(default_factory=QuadrotorParams)
    """Vehicle dynamics, identical for every vehicle."""
    brush: BrushParams = field(default_factory=BrushParams)
    """Brush geometry and width model."""
    wind: WindParams = field(default_factory=WindParams)
    """Wind statistics (each vehicle draws its own gusts)."""
    mocap: MocapParams = field(default_factory=MocapParams)
    """Motion-capture latency and noise."""
    board_height_m: float = 0.0
    """Height of the horizontal writing board surface in [m] (world z); it spans the world."""
    control_rate_hz: float = 100.0
    """Rate at which inner-loop commands arrive and the world is stepped, in [Hz]."""
    physics_substeps: int = 4
    """Physics integration steps per control tick."""

    def __post_init__(self) -> None:
        positive("control_rate_hz", self.control_rate_hz)
        if self.physics_substeps < 1:
            raise SimError("must be at least 1", field="physics_substeps")

    @property
    def dt_s(self) -> float:
        """Control tick in [s]."""
        return 1.0 / self.control_rate_hz

    @property
    def physics_dt_s(self) -> float:
        """Physics step in [s]."""
        return self.dt_s / self.physics_substeps

"""Physical figures of the hexarotor sponge writer (one place; the world, planner and controller
read them from here)."""

from __future__ import annotations

from dataclasses import dataclass, field

from vehicles.hexarotor_sponge import defaults
from vehicles.hexarotor_sponge.pen import PenCurve

GRAVITY_MPS2 = 9.81
"""Standard gravity in [m/s^2]."""


@dataclass(frozen=True)
class HexarotorParams:
    """A fully-actuated hexarotor with a one-link arm ending in a sponge pen on a spring."""

    base_mass_kg: float = 3.2
    """Mass of the vehicle body with its rotors in [kg]."""
    base_inertia_kgm2: tuple[float, float, float] = (0.06, 0.06, 0.11)
    """Principal moments of inertia of the body in [kg m^2] (body x front, y left, z up)."""
    arm_mass_kg: float = 0.25
    """Mass of the arm (a rod from the F/T sensor forward) in [kg]."""
    pen_mass_kg: float = 0.03
    """Mass of the sliding sponge cone in [kg]."""
    rotor_radius_m: float = 0.28
    """Distance of each rotor from the body centre in [m]."""
    rotor_tilt_rad: float = defaults.ROTOR_TILT_RAD
    """Tilt of each rotor about its arm, alternating sign, in [rad] (29.79 deg; the paper's
    about 30 deg): what makes the body fully actuated."""
    thrust_max_n: float = defaults.THRUST_MAX_N
    """Largest thrust of one rotor in [N] (smallest is 0)."""
    drag_torque_m: float = 0.016
    """Rotor drag torque per thrust in [N m / N] (alternating spin directions)."""
    arm_base_m_body: tuple[float, float, float] = (0.12, 0.0, 0.0)
    """F/T sensor (arm root) in the body frame in [m]."""
    arm_length_m: float = defaults.ARM_LENGTH_M
    """From the F/T sensor to the pen tip (spring at its stop) in [m], along body x."""
    pen_stiffness_npm: float = defaults.PEN_STIFFNESS_NPM
    """Pen spring stiffness in [N/m]."""
    pen_preload_n: float = defaults.PEN_PRELOAD_N
    """Spring preload in [N]: below it the pen does not slide back."""
    pen_damping_nspm: float = 10.0
    """Damping of the pen's slide in [N s/m] (the sponge)."""
    pen_travel_m: float = 0.03
    """Longest slide of the pen into its holder in [m]."""
    sponge_impedance_touch: float = 0.5
    """MuJoCo's constraint impedance of the sponge's contact where it just touches the wall
    (``solimp`` dmin of its geom, rising to 0.95 at 1 mm; MuJoCo mixes it with the wall's
    0.9): the sponge gives more at first touch. With 0.9 on both the sliding 30 g sponge
    chatters at 20 Hz on the 2 ms physics step (+-0.5 N; letter I without wind or noise: 0.31 N
    of the 0.33 N force RMSE), an artefact of the step: it shrinks as the step does (0.15 N at
    1 ms, 0.09 N at 0.5 ms). With 0.5 the chatter is gone (3 N at 20 cm/s: 0.40 -> 0.0002 N
    after a 0.1 s average) and the tip presses 0.5 mm into the wall instead of 0.8 mm."""
    wall_friction: float = defaults.WALL_FRICTION
    """Coulomb friction coefficient of pen on wall (measured in the paper)."""
    pen: PenCurve = field(default_factory=PenCurve)
    """Force -> line width calibration."""

    @property
    def mass_kg(self) -> float:
        """Total mass in [kg]."""
        return self.base_mass_kg + self.arm_mass_kg + self.pen_mass_kg

    @property
    def tip_m_body(self) -> tuple[float, float, float]:
        """Nominal pen tip (spring at its stop) in the body frame in [m]."""
        x, y, z = self.arm_base_m_body
        return (x + self.arm_length_m, y, z)

    @property
    def arm_com_m_sensor(self) -> tuple[float, float, float]:
        """Centre of mass of arm and pen together, from the F/T sensor, sensor axes, in [m]."""
        arm_x = self.arm_mass_kg * self.arm_length_m / 2.0
        pen_x = self.pen_mass_kg * (self.arm_length_m - 0.02)
        return ((arm_x + pen_x) / (self.arm_mass_kg + self.pen_mass_kg), 0.0, 0.0)

    @property
    def com_m_body(self) -> tuple[float, float, float]:
        """Centre of mass of the whole vehicle in the body frame in [m] (the arm shifts it)."""
        m_arm = self.arm_mass_kg + self.pen_mass_kg
        x = m_arm * (self.arm_base_m_body[0] + self.arm_com_m_sensor[0]) / self.mass_kg
        return (x, 0.0, 0.0)

    def compression_m(self, force_n: float) -> float:
        """Pen slide in [m] at a normal force in [N] (0 below the preload)."""
        return max(force_n - self.pen_preload_n, 0.0) / self.pen_stiffness_npm

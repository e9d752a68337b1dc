"""Vehicle limits of a ~1 kg writing quadrotor and their split into per-axis bounds (eq. 12-14)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from planner.errors import PlannerError

GRAVITY_MPS2 = 9.80665
"""Standard gravity in [m/s^2]; world gravity vector is (0, 0, -g) in ENU."""

DEFAULT_MASS_KG = 1.0


@dataclass(frozen=True)
class VehicleLimits:
    """Limits the planned reference must respect.

    Defaults suit the Airshow quadrotor (about 1 kg, 10-inch propellers) writing characters of
    about 1 m: gentle accelerations keep the attitude (and the brush pendulum) small; thrust is
    twice the weight; the body-rate bound of eq. (15) stays far below the 25 rad/s inner loop.
    """

    a_max_mps2: tuple[float, float, float] = (0.8, 0.8, 0.5)
    """Largest |acceleration| per world axis x, y, z in [m/s^2] (alpha_i of eq. 13)."""
    v_max_mps: float = 0.5
    """Largest speed ||v|| in [m/s]."""
    mass_kg: float = DEFAULT_MASS_KG
    """Vehicle mass in [kg] (for thrust, eq. 12)."""
    thrust_max_n: float = 2.0 * DEFAULT_MASS_KG * GRAVITY_MPS2
    """Largest collective thrust in [N] (f_max of eq. 12 times the mass)."""
    body_rate_max_radps: float = 3.0
    """Largest allowed body-rate bound of eq. (15) in [rad/s]."""

    def __post_init__(self) -> None:
        if len(self.a_max_mps2) != 3 or min(self.a_max_mps2) <= 0.0:
            raise PlannerError(f"must be three values > 0, got {self.a_max_mps2}", field="a_max")
        for name in ("v_max_mps", "mass_kg", "thrust_max_n", "body_rate_max_radps"):
            if not getattr(self, name) > 0.0:
                raise PlannerError(f"must be > 0, got {getattr(self, name)}", field=name)
        if self.thrust_split_mps2()[2] <= GRAVITY_MPS2:
            raise PlannerError(
                f"thrust {self.thrust_max_n:.2f} N cannot hold {self.mass_kg:.2f} kg while"
                f" accelerating {self.a_max_mps2[0]}, {self.a_max_mps2[1]} m/s^2 sideways",
                field="thrust_max",
            )

    @property
    def specific_thrust_max_mps2(self) -> float:
        """``f_max`` of eq. (12) as an acceleration: thrust_max / mass in [m/s^2]."""
        return self.thrust_max_n / self.mass_kg

    def thrust_split_mps2(self) -> tuple[float, float, float]:
        """``alpha_i`` of eq. (13)-(14): x, y get a_max; z gets the rest of ``f_max^2``."""
        ax, ay, _ = self.a_max_mps2
        rest = self.specific_thrust_max_mps2**2 - ax**2 - ay**2
        return (ax, ay, math.sqrt(rest) if rest > 0.0 else 0.0)

    def accel_bounds_mps2(self) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """Per-axis (lower, upper) acceleration bounds combining a_max with eq. (13).

        z: ``|a_z + g| <= alpha_3`` and thrust >= 0 (``a_z >= -g``) intersected with ``|a_z| <=
        a_max_z``.
        """
        ax, ay, az = self.a_max_mps2
        alpha_z = self.thrust_split_mps2()[2]
        lower_z = max(-az, -GRAVITY_MPS2, -alpha_z - GRAVITY_MPS2)
        upper_z = min(az, alpha_z - GRAVITY_MPS2)
        return (-ax, -ay, lower_z), (ax, ay, upper_z)

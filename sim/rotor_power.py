"""Electrical power of rotors holding a thrust, from momentum theory (pure).

Ideal induced power of a rotor of disk area ``A`` producing thrust ``T`` in hover (Leishman,
*Principles of Helicopter Aerodynamics*, 2nd ed., Cambridge University Press 2006, section 2.2,
eq. 2.14)::

    P_ideal = T^(3/2) / sqrt(2 rho A)

The figure of merit ``FM = P_ideal / P_shaft`` (ibid., section 2.3.1) takes the rotor's profile
losses; the drive efficiency (motor and speed controller) turns shaft power into the power drawn
from the battery. Rotors of a multirotor share the thrust equally.
"""

from __future__ import annotations

import math

from sim.errors import SimError
from sim.params import positive

SEA_LEVEL_AIR_DENSITY_KGPM3 = 1.225
"""ISA sea-level air density in [kg/m^3]."""
SMALL_ROTOR_FIGURE_OF_MERIT = 0.55
"""Figure of merit of small (10-inch class) propellers in hover: measured figures of merit of
micro-air-vehicle rotors lie between about 0.45 and 0.65 (Bohorquez, Samuel, Sirohi, Pines,
Rudd, Perel, "Design, analysis and hover performance of a rotary wing micro air vehicle",
J. American Helicopter Society 48(2), 2003), well below the 0.7-0.8 of full-scale rotors
(Leishman 2006, section 2.3.1); the middle of that range."""
DRIVE_EFFICIENCY = 0.80
"""Shaft power over battery power of a brushless motor and its speed controller near hover
throttle: motor efficiencies of about 0.80-0.85 and controllers of about 0.95 (Bershadsky,
Haviland, Johnson, "Electric multirotor UAV propulsion system sizing for performance prediction
and design optimization", AIAA SciTech 2016-0581)."""


def rotor_power_w(
    thrust_n: float,
    rotors: int,
    rotor_radius_m: float,
    *,
    figure_of_merit: float = SMALL_ROTOR_FIGURE_OF_MERIT,
    drive_efficiency: float = DRIVE_EFFICIENCY,
    air_density_kgpm3: float = SEA_LEVEL_AIR_DENSITY_KGPM3,
) -> float:
    """Battery power in [W] of ``rotors`` equal rotors of radius ``rotor_radius_m`` [m] producing
    ``thrust_n`` [N] together (0 without thrust)."""
    positive("rotor_radius_m", rotor_radius_m)
    positive("figure_of_merit", figure_of_merit)
    positive("drive_efficiency", drive_efficiency)
    if rotors < 1:
        raise SimError(f"must be >= 1, got {rotors}", field="rotors")
    if thrust_n <= 0.0:
        return 0.0
    per_rotor_n = thrust_n / rotors
    area_m2 = math.pi * rotor_radius_m**2
    ideal_w = math.pow(per_rotor_n, 1.5) / math.sqrt(2.0 * air_density_kgpm3 * area_m2)
    return rotors * ideal_w / (figure_of_merit * drive_efficiency)

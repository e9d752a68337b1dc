"""The Flying Calligrapher hexarotor's battery, and what it draws in each phase.

Guo et al. 2024 give neither the pack nor the propellers. Its six rotors sit 0.28 m from the
centre, 60 deg apart, so neighbours are 0.28 m apart: 10-inch (0.254 m) propellers are the
largest common size that fits; each is tilted ``rotor_tilt_rad`` (about 30 deg) about its arm, so
holding the weight takes ``m g / cos(tilt)`` of thrust in all. Momentum theory
(:mod:`sim.rotor_power`) at the room's own mass (3.48 kg): 650 W at the rotors, 656 W with the
avionics. A 6S 5000 mAh pack (an assumption: a usual pack of a 3-4 kg hexarotor; 114 Wh) gives it
about 10 minutes.

Writing presses the sponge on the wall with up to ``PEN_FORCE_MAX_N`` besides the weight: the
rotors' force grows to ``sqrt((m g)^2 + F^2)``. Pen-up moves are at 0.2 m/s, well within hover
(transit draws the hover power).
"""

from __future__ import annotations

import math

from sim.battery import LipoPack, PhasePowers, VehicleBattery
from sim.rotor_power import rotor_power_w
from vehicles.hexarotor_sponge import defaults
from vehicles.hexarotor_sponge.params import GRAVITY_MPS2, HexarotorParams
from vehicles.quadrotor_brush.battery import AVIONICS_W, CELL_RESISTANCE_OHM

PROPELLER_RADIUS_M = 0.127
"""10-inch propellers, [m] (the largest that fit 0.28 m apart)."""
PACK = LipoPack(cells_in_series=6, capacity_mah=5000.0, cell_resistance_ohm=CELL_RESISTANCE_OHM)


def rotors_w(params: HexarotorParams, contact_force_n: float) -> float:
    """Battery power in [W] of the tilted rotors holding the vehicle and pressing the wall with
    ``contact_force_n`` [N]."""
    weight_n = params.mass_kg * GRAVITY_MPS2
    force_n = math.hypot(weight_n, contact_force_n)
    return rotor_power_w(force_n / math.cos(params.rotor_tilt_rad), 6, PROPELLER_RADIUS_M)


_PARAMS = HexarotorParams()
_HOVER_W = AVIONICS_W + rotors_w(_PARAMS, 0.0)
BATTERY = VehicleBattery(
    pack=PACK,
    power_w=PhasePowers(
        rest_w=AVIONICS_W,
        hover_w=_HOVER_W,
        transit_w=_HOVER_W,
        writing_w=AVIONICS_W + rotors_w(_PARAMS, defaults.PEN_FORCE_MAX_N),
    ),
    cruise="hover",
)
"""What the wall writer carries and draws."""

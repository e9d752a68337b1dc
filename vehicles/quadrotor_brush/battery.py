"""The Airshow quadrotor's battery: a 4S 3000 mAh LiPo, and what it draws in each phase.

Phang et al. 2015 (section 2) give the vehicle, not its pack: about 1 kg, four 10-inch
propellers. A 4S 3000 mAh pack is the usual one of that class (issue 32's figure). Hover power
from momentum theory (:mod:`sim.rotor_power`) at the room's own mass and propeller radius
(:class:`~vehicles.quadrotor_brush.params.QuadrotorParams`): 99 W at the rotors (figure of merit
0.55, drive efficiency 0.80), 105 W with the avionics, 6.5 A from the full pack; about 26 minutes
from full to empty, 20 to the show's default reserve.

Transit and writing draw the hover power too: pen-up moves are at most about 1 m/s, where the
induced velocity of hover (4.4 m/s at this disk loading) falls by about 1 % (Glauert's
forward-flight inflow, Leishman 2006, section 2.14) and the drag power (0.35 N/(m/s) x (1 m/s)^2)
is 0.4 W; the brush rests on its board through a bearing and lifts nothing.
"""

from __future__ import annotations

from sim.battery import LipoPack, PhasePowers, VehicleBattery
from sim.rotor_power import rotor_power_w
from vehicles.quadrotor_brush.params import QuadrotorParams

AVIONICS_W = 6.0
"""Flight controller, receiver and a Raspberry Pi 4-class companion computer at work, [W] (the
Raspberry Pi 4 Model B's supply is rated 5 V 3 A; it draws about 3-6 W busy, the flight
controller and receiver 1-2 W more)."""
CELL_RESISTANCE_OHM = 0.008
"""Internal resistance of one cell, [Ohm]: 5-8 mOhm is a healthy pack in normal use, 8-12 mOhm an
aging one (per-cell table of blog.uavmodel.com, "FPV LiPo internal resistance guide"); the
boundary, for a pack used for a season."""
PACK = LipoPack(cells_in_series=4, capacity_mah=3000.0, cell_resistance_ohm=CELL_RESISTANCE_OHM)


def hover_w(params: QuadrotorParams) -> float:
    """Battery power in [W] of the quadrotor hovering: its rotors and avionics."""
    weight_n = params.mass_kg * params.gravity_mps2
    return AVIONICS_W + rotor_power_w(weight_n, 4, params.rotor_radius_m)


_HOVER_W = hover_w(QuadrotorParams())
BATTERY = VehicleBattery(
    pack=PACK,
    power_w=PhasePowers(
        rest_w=AVIONICS_W, hover_w=_HOVER_W, transit_w=_HOVER_W, writing_w=_HOVER_W
    ),
    cruise="hover",
)
"""What the Airshow quadrotor carries and draws."""

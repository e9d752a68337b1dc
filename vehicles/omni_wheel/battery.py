"""The step-climbing ground writer's battery, and what it draws in each phase.

Chugo's paper gives the vehicle (Table 1: 21.6 kg, seven 132 mm wheels, 0.25 m/s), not its
pack. A 6S 5000 mAh LiPo is assumed (the same pack as the hexarotor's, so a show needs one
kind of pack).

Driving on a level floor takes the rolling resistance ``C_rr m g v`` through the drive
(:data:`sim.rotor_power.DRIVE_EFFICIENCY`); ``C_rr`` = 0.03 for hard wheels on a hard floor with
the free rollers' bearings besides (hard rubber on concrete is 0.01-0.02, Gillespie,
*Fundamentals of Vehicle Dynamics*, SAE 1992, table 4.1; the rollers' bearings add to it). Standing
with its motors on, the seven wheel controllers hold position: ``MOTOR_HOLD_W`` each. The marker
rubs the floor with about 1 N (Coulomb friction of a felt tip).
"""

from __future__ import annotations

from sim.battery import LipoPack, PhasePowers, VehicleBattery
from sim.rotor_power import DRIVE_EFFICIENCY
from vehicles.omni_wheel.geometry import OmniGeometry
from vehicles.quadrotor_brush.battery import AVIONICS_W, CELL_RESISTANCE_OHM

GRAVITY_MPS2 = 9.81
ROLLING_RESISTANCE = 0.03
"""Rolling resistance coefficient of the omni wheels on the floor (see the module)."""
MOTOR_HOLD_W = 1.0
"""A wheel's motor controller powered and holding its wheel, [W] (an assumption: quiescent
drive electronics of a small DC servo)."""
MARKER_DRAG_N = 1.0
"""The marker's friction on the floor, [N] (an assumption)."""
PACK = LipoPack(cells_in_series=6, capacity_mah=5000.0, cell_resistance_ohm=CELL_RESISTANCE_OHM)


def driving_w(geometry: OmniGeometry, drag_n: float = 0.0) -> float:
    """Battery power in [W] to drive at the running speed against rolling resistance and
    ``drag_n`` [N] more."""
    mass_kg = geometry.front_mass_kg + geometry.rear_mass_kg
    resist_n = ROLLING_RESISTANCE * mass_kg * GRAVITY_MPS2 + drag_n
    return resist_n * geometry.running_speed_mps / DRIVE_EFFICIENCY


_GEOMETRY = OmniGeometry()
_STANDING_W = AVIONICS_W + 7 * MOTOR_HOLD_W
BATTERY = VehicleBattery(
    pack=PACK,
    power_w=PhasePowers(
        rest_w=AVIONICS_W,
        hover_w=_STANDING_W,
        transit_w=_STANDING_W + driving_w(_GEOMETRY),
        writing_w=_STANDING_W + driving_w(_GEOMETRY, MARKER_DRAG_N),
    ),
    cruise="transit",
)
"""What the ground writer carries and draws."""

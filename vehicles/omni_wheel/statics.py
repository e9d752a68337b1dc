"""Quasi-static bounds of a climb (planar, level body, pure): the loads each axle carries, the lift
friction on a step's riser can give an axle, the wheel torque that lift takes, and how high the
frames must sit to clear a step's edge.

A wheel on a riser higher than its radius touches it at axle height: the vehicle's push ``N``
presses it on, and the wheel, driven, climbs on the riser's friction, at most ``mu N``. The push
comes from the traction of the x-driving wheels still on a floor, at most ``mu`` times the load
they carry. Phases: the front axle on the riser (middle and rear wheels push), then the middle
axle (front wheels on top pull, rear wheels push), then the rear axle (front and middle wheels
pull). The front-centre wheel drives sideways: its rollers roll freely along x and up the riser,
so its share of the front axle's load (a third) gives no traction and no lift.

Loads are those of the level vehicle: the front part hangs on free joint 1 (its front axle
carries its moment about the joint), the rear part rests on its two axles with the joint's share.
Geometry and masses from :class:`OmniGeometry` (Table 1 and its readings).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from planner.limits import GRAVITY_MPS2
from vehicles.omni_wheel.geometry import FRONT_PART, OmniGeometry
from vehicles.omni_wheel.model import HUB_MASS_KG, ROLLER_MASS_KG

PAPER_CLIMB_M = 0.152
"""Highest step in [m] the prototype climbed (section 3.3, proposed method)."""


@dataclass(frozen=True)
class AxleLoads:
    """Vertical loads in [N] of the level vehicle on its three axles."""

    front_n: float
    """Front axle (three wheels, one of them driving sideways)."""
    middle_n: float
    """Middle axle (two wheels)."""
    rear_n: float
    """Rear axle (two wheels)."""


@dataclass(frozen=True)
class RiserPhase:
    """One axle on the riser."""

    axle: str
    """``front``, ``middle`` or ``rear``."""
    lift_needed_n: float
    """Load in [N] the riser's friction must lift (the axle's load)."""
    lift_available_n: float
    """Most the riser's friction gives in [N]: ``mu`` times the push, itself at most ``mu``
    times the load on the pushing x-driving wheels."""
    torque_nm: float
    """Torque in [N m] each climbing x-driving wheel of that axle needs for ``lift_needed_n``."""

    @property
    def possible(self) -> bool:
        """Friction can lift the axle."""
        return self.lift_available_n >= self.lift_needed_n


def wheel_mass_kg(geometry: OmniGeometry) -> float:
    """Mass in [kg] of one wheel (hub and rollers, ``model``)."""
    return HUB_MASS_KG + geometry.rollers_per_wheel * ROLLER_MASS_KG


def axle_loads(geometry: OmniGeometry) -> AxleLoads:
    """The level vehicle's axle loads (see the module docstring)."""
    g, wheel = geometry, wheel_mass_kg(geometry)
    n_front = int(FRONT_PART.sum())
    front_frame_kg = g.front_mass_kg - n_front * wheel
    rear_frame_kg = g.rear_mass_kg - (7 - n_front) * wheel
    front_n = GRAVITY_MPS2 * (
        front_frame_kg * g.front_frame_com_m / g.front_link_m + n_front * wheel
    )
    joint_n = GRAVITY_MPS2 * g.front_mass_kg - front_n
    d = g.middle_rear_m
    middle_n = (
        GRAVITY_MPS2 * rear_frame_kg * (g.rear_frame_com_x_m + d)
        + GRAVITY_MPS2 * 2 * wheel * d
        + joint_n * (g.joint1_x_m + d)
    ) / d
    rear_n = GRAVITY_MPS2 * g.rear_mass_kg + joint_n - middle_n
    return AxleLoads(front_n, middle_n, rear_n)


def riser_phases(geometry: OmniGeometry, friction: float) -> tuple[RiserPhase, ...]:
    """The three phases of a climb over a riser higher than the wheel radius, with roller
    ``friction`` on floor and riser."""
    loads = axle_loads(geometry)
    traction = {  # load on each axle's x-driving wheels
        "front": 2.0 / 3.0 * loads.front_n,
        "middle": loads.middle_n,
        "rear": loads.rear_n,
    }
    needed = {"front": loads.front_n, "middle": loads.middle_n, "rear": loads.rear_n}
    r = geometry.wheel_radius_m
    return tuple(
        RiserPhase(
            axle,
            needed[axle],
            friction * friction * sum(v for k, v in traction.items() if k != axle),
            0.5 * needed[axle] * r,  # two x-driving wheels lift each axle
        )
        for axle in ("front", "middle", "rear")
    )


def required_torque_nm(geometry: OmniGeometry) -> float:
    """Largest torque in [N m] one wheel needs to lift its axle up a riser (over the phases)."""
    return max(p.torque_nm for p in riser_phases(geometry, 1.0))


def min_frame_clearance_m(geometry: OmniGeometry, step_height_m: float) -> float:
    """Lowest height in [m] of the frames' underside above the axle line that clears a step of
    ``step_height_m``: the rear frame with its rear wheels at the riser and its middle wheels on
    top, and the front linkage with the middle wheels at the riser (joint 1 at axle height,
    ``middle_wheel_gap`` behind it) and its front wheels on top."""
    g, h, r = geometry, step_height_m, geometry.wheel_radius_m
    d = g.middle_rear_m
    # rear frame: the axle line runs from the middle axle on top to the rear one at the riser
    rear = h - (r + h * (1.0 - (d - r) / d))
    # front linkage: pitched up by asin(h / l) about joint 1, which stands this far from the riser
    gap = r - g.joint1_x_m
    pitch = math.asin(min(1.0, h / g.front_link_m))
    front = -gap * math.sin(pitch) + (h - r) * math.cos(pitch)
    return max(rear, front, 0.0)

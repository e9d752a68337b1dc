"""The prototype and its terrain as MuJoCo MJCF, built in code.

Each wheel is a hub on an actuated hinge carrying twelve free rollers (capsules on their own
hinges, axes tangent to the rim): the rim can only push along the wheel's drive direction, while
the rollers let the wheel slide freely along its axle. The rollers and the two frames touch the
terrain (collision classes: rollers 1, frames 2, terrain both), nothing of a vehicle touches
another part of it or another vehicle. Each frame is a plate between the wheels (y within
``FRAME_HALF_WIDTH_M``) from free joint 1 along its part's length (Table 1: front linkage to
the front axle, rear frame 400 mm back from the joint), its underside
``geometry.frame_clearance_m`` above the axle line (its basis: ``geometry``). Each frame's mass
sits at its mass centre as ``geometry`` reads it (an explicit inertial, independent of the
collision plate). A roller's friction rules its contacts (higher priority than the terrain's),
so the simulation can lower it to the dynamic coefficient while the roller slides (``sim``); a
frame scraping an edge slides with Table 1's dynamic coefficient (the vehicle's material on the
ground, the only one the paper gives).

Angles are in radians (MJCF's default is degrees: joint ranges would be read as such).

Terrain: a floor plane and, for each step, a box whose top is the height of the floor beyond the
step edge (steps lie across x, the direction of travel: ``vehicles.omni_wheel.terrain``).
"""

from __future__ import annotations

import math

import numpy as np

from vehicles.omni_wheel.geometry import FRONT_PART, WHEEL_NAMES, OmniGeometry
from vehicles.omni_wheel.terrain import Terrain

ROLLER_RADIUS_M = 0.016
"""Radius in [m] of a free roller (capsule)."""
HUB_MASS_KG = 0.25
"""Mass in [kg] of a wheel hub with its motor's rotating parts."""
ROLLER_MASS_KG = 0.015
"""Mass in [kg] of one free roller."""
FRAME_HALF_WIDTH_M = 0.1
"""Half width in [m] of the frame plates (inside the side wheels' hubs at 0.15 m)."""
FRAME_THICKNESS_M = 0.04
"""Thickness in [m] of the frame plates."""
FRAME_COM_ABOVE_AXLE_M = 0.05
"""Height in [m] of the frames' mass centres above the axle line (batteries and electronics on
the frames; an estimate: the paper gives no heights but joint 1's)."""
FRAME_FRICTION = 0.25
"""Friction of a frame on an edge it scrapes (Table 1's dynamic coefficient)."""
PHYSICS_TIMESTEP_S = 0.001
"""MuJoCo time step in [s]."""


def _f(values: tuple[float, ...] | np.ndarray) -> str:
    return " ".join(f"{float(v):.6g}" for v in values)


def _terrain_xml(terrain: Terrain, friction: float) -> str:
    fr = f'friction="{friction} 0.005 0.0001"'
    parts = [
        f'<geom name="floor" type="plane" size="0 0 1" contype="0" conaffinity="3" {fr}'
        ' rgba=".8 .8 .75 1"/>'
    ]
    for k, step in enumerate(terrain.steps):
        end = (
            terrain.steps[k + 1].x_m if k + 1 < len(terrain.steps) else step.x_m + terrain.length_m
        )
        if step.height_m <= 0.0:
            continue
        half = (0.5 * (end - step.x_m), terrain.half_width_m, 0.5 * step.height_m)
        centre = (0.5 * (end + step.x_m), 0.0, 0.5 * step.height_m)
        parts.append(
            f'<geom name="step{k}" type="box" size="{_f(half)}" pos="{_f(centre)}" contype="0"'
            f' conaffinity="3" {fr} rgba=".6 .6 .6 1"/>'
        )
    return "\n".join(parts)


def _wheel_xml(prefix: str, name: str, pos: np.ndarray, axle: np.ndarray, g: OmniGeometry) -> str:
    """A hub on its motor hinge with twelve roller bodies (capsule + free hinge each)."""
    d = g.wheel_radius_m - ROLLER_RADIUS_M
    half_len = d * math.tan(math.pi / g.rollers_per_wheel)
    spoke = np.array([0.0, 0.0, 1.0])
    other = np.cross(axle, spoke)
    fr = f'friction="{g.friction_static} 0.005 0.0001"'
    rollers = []
    for k in range(g.rollers_per_wheel):
        phi = 2.0 * math.pi * k / g.rollers_per_wheel
        radial = math.cos(phi) * spoke + math.sin(phi) * other
        tangent = np.cross(axle, radial)
        rollers.append(
            f'<body pos="{_f(d * radial)}"><joint type="hinge" axis="{_f(tangent)}"'
            ' damping="0.0005" armature="0.0001"/>'
            f'<geom type="capsule" size="{ROLLER_RADIUS_M}" fromto="{_f(-half_len * tangent)}'
            f' {_f(half_len * tangent)}" mass="{ROLLER_MASS_KG}" contype="1" conaffinity="0"'
            f' priority="1" {fr} condim="3" rgba=".15 .15 .15 1"/></body>'
        )
    hub_to = 0.012 * axle
    return (
        f'<body name="{prefix}{name}" pos="{_f(pos)}">'
        f'<joint name="{prefix}{name}" type="hinge" axis="{_f(axle)}" armature="0.01"'
        ' damping="0.02"/>'
        f'<geom type="cylinder" size="{0.7 * d}" fromto="{_f(-hub_to)} {_f(hub_to)}"'
        f' mass="{HUB_MASS_KG}" contype="0" conaffinity="0" rgba=".8 .3 .1 1"/>'
        + "".join(rollers)
        + "</body>"
    )


def _frame_xml(
    name: str, x_from_m: float, x_to_m: float, mass_kg: float, com_x_m: float, g: OmniGeometry
) -> str:
    """A frame's mass (explicit inertial at its mass centre) and its colliding plate from
    ``x_from_m`` to ``x_to_m`` in its body's frame, ``g.frame_clearance_m`` above the axle line."""
    length = x_to_m - x_from_m
    w, t = 2.0 * FRAME_HALF_WIDTH_M, FRAME_THICKNESS_M
    inertia = (mass_kg / 12.0) * np.array([w * w + t * t, length**2 + t * t, length**2 + w * w])
    half = (0.5 * length, FRAME_HALF_WIDTH_M, 0.5 * t)
    centre = (0.5 * (x_from_m + x_to_m), 0.0, g.frame_clearance_m + 0.5 * t)
    return (
        f'<inertial pos="{_f((com_x_m, 0.0, FRAME_COM_ABOVE_AXLE_M))}" mass="{mass_kg:.6g}"'
        f' diaginertia="{_f(inertia)}"/>'
        f'<geom name="{name}" type="box" size="{_f(half)}" pos="{_f(centre)}" contype="2"'
        f' conaffinity="0" priority="1" friction="{FRAME_FRICTION} 0.005 0.0001"'
        ' rgba=".2 .4 .8 1"/>'
    )


def _vehicle_xml(
    prefix: str, start_m: tuple[float, float, float], yaw_rad: float, g: OmniGeometry
) -> str:
    wheel_mass = HUB_MASS_KG + g.rollers_per_wheel * ROLLER_MASS_KG
    rear_frame = g.rear_mass_kg - wheel_mass * int(np.sum(~FRONT_PART))
    front_frame = g.front_mass_kg - wheel_mass * int(np.sum(FRONT_PART))
    pos, axles = g.wheel_positions_m(), g.axle_directions()
    joint = np.array([g.joint1_x_m, 0.0, 0.0])
    rear_wheels = "".join(
        _wheel_xml(prefix, WHEEL_NAMES[i], pos[i], axles[i], g)
        for i in range(7)
        if not FRONT_PART[i]
    )
    front_wheels = "".join(
        _wheel_xml(prefix, WHEEL_NAMES[i], pos[i] - joint, axles[i], g)
        for i in range(7)
        if FRONT_PART[i]
    )
    x, y, z = start_m
    quat = (math.cos(0.5 * yaw_rad), 0.0, 0.0, math.sin(0.5 * yaw_rad))
    tail = g.joint1_x_m - g.rear_link_m
    rear = _frame_xml(
        f"{prefix}rear_frame", tail, g.joint1_x_m, rear_frame, g.rear_frame_com_x_m, g
    )
    front = _frame_xml(
        f"{prefix}front_frame", 0.0, g.front_link_m, front_frame, g.front_frame_com_m, g
    )
    return (
        f'<body name="{prefix}rear" pos="{_f((x, y, z))}" quat="{_f(quat)}">'
        f'<freejoint name="{prefix}base"/>'
        + rear
        + f'<site name="{prefix}imu" pos="0 0 0"/>'
        + rear_wheels
        + f'<body name="{prefix}front" pos="{_f(joint)}">'
        f'<joint name="{prefix}joint1_pitch" type="hinge" axis="0 1 0" range="-0.9 0.9"'
        ' limited="true" damping="0.2"/>'
        f'<joint name="{prefix}joint1_roll" type="hinge" axis="1 0 0" range="-0.4 0.4"'
        ' limited="true" damping="0.2"/>'
        + front
        + f'<site name="{prefix}pen" pos="{_f((g.front_link_m * 0.5, 0.0, 0.0))}"/>'
        + front_wheels
        + "</body></body>"
    )


def vehicle_prefix(index: int) -> str:
    """Name prefix of vehicle ``index`` in a multi-vehicle model."""
    return f"v{index}_"


def build_mjcf(
    geometry: OmniGeometry,
    terrain: Terrain,
    starts: tuple[tuple[float, float, float, float], ...],
) -> str:
    """MJCF of ``terrain`` with one vehicle per start ``(x, y, floor height, yaw)`` in [m, rad]
    (the vehicle rests on its wheels there)."""
    bodies = "".join(
        _vehicle_xml(vehicle_prefix(k), (x, y, h + geometry.wheel_radius_m + 0.002), yaw, geometry)
        for k, (x, y, h, yaw) in enumerate(starts)
    )
    torque = geometry.motor_torque_max_nm
    motors = "".join(
        f'<motor name="{vehicle_prefix(k)}{w}" joint="{vehicle_prefix(k)}{w}"'
        f' ctrlrange="{-torque} {torque}" ctrllimited="true"/>'
        for k in range(len(starts))
        for w in WHEEL_NAMES
    )
    return (
        '<mujoco model="omni_wheel">'
        '<compiler angle="radian"/>'
        f'<option timestep="{PHYSICS_TIMESTEP_S}" integrator="implicitfast" cone="elliptic"/>'
        "<worldbody>"
        f"{_terrain_xml(terrain, geometry.friction_static)}{bodies}"
        "</worldbody>"
        f"<actuator>{motors}</actuator>"
        "</mujoco>"
    )

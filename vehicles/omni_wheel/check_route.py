"""Whether a ground writer can reach a floor area and write there (pure, light: read by the show
file's validation and the orchestrator's assignment as well as the room).

:func:`check_route` refuses, with one line naming the area and the step, a route with a step
higher than the vehicle climbs, a floor area off the terrain or straddling a step edge, a floor
area whose height is not the floor's, or one too far away. Routes go sideways on the level they
start on, then along x over the steps (``vehicles.omni_wheel.route``).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from vehicles.omni_wheel.terrain import Step, Terrain

MAX_STEP_HEIGHT_M = 0.05
"""Highest step in [m] the writer is allowed to cross: climbed with margin in MuJoCo with rubber
rollers and the proposed method (the model as read climbs about 70 mm, benchmarks/bench_ground.py:
above the wheel radius the rear wheels stall at the riser, the friction of the wheels on top
too small to press them on hard enough; the paper's 0.1 m step needs the rear mass centre read
further forward, ``geometry``)."""
MAX_ROUTE_M = 60.0
"""Longest route in [m] from the start to a floor area."""


class RouteError(ValueError):
    """A floor area the ground writer cannot reach or write on; the message says which and why."""


@dataclass(frozen=True)
class FloorArea:
    """Where a ground writer is sent: a floor area's centre and half size."""

    name: str
    """The area's name in the show."""
    centre_m_enu: tuple[float, float, float]
    """Centre of the area in [m], world ENU (its height must be the floor's there)."""
    half_size_m: float
    """Half the side in [m] of the square the vehicle covers while writing there."""


def check_route(start_m_enu: tuple[float, float, float], area: FloorArea, terrain: Terrain) -> None:
    """Raise :class:`RouteError` when ``area`` cannot be reached from ``start_m_enu`` or written on
    (see the module docstring); return quietly otherwise."""
    x, y, z = area.centre_m_enu
    where = f"floor area {area.name!r}"
    if abs(y) + area.half_size_m > terrain.half_width_m:
        raise RouteError(
            f"{where} at y={y:.2f} m lies off the terrain (|y| <= {terrain.half_width_m:.1f} m)"
        )
    floor = terrain.height_at_m(x)
    if abs(z - floor) > 0.005:
        raise RouteError(
            f"{where} is at height {z:.3f} m but the floor there is {floor:.3f} m high"
        )
    for step in terrain.steps:
        if abs(step.x_m - x) < area.half_size_m:
            raise RouteError(f"{where} straddles the step edge at x={step.x_m:.2f} m")
    length = abs(x - start_m_enu[0]) + abs(y - start_m_enu[1])
    if length > MAX_ROUTE_M:
        raise RouteError(
            f"{where} is out of reach: {length:.1f} m of route, at most {MAX_ROUTE_M:.0f} m"
        )
    lo, hi = sorted((start_m_enu[0], x))
    level = terrain.height_at_m(lo)
    for step in terrain.steps:
        if lo < step.x_m <= hi:
            rise = abs(step.height_m - level)
            if rise > MAX_STEP_HEIGHT_M + 1e-9:
                raise RouteError(
                    f"{where} is out of reach: the step at x={step.x_m:.2f} m is {rise:.3f} m high,"
                    f" the vehicle climbs at most {MAX_STEP_HEIGHT_M:.3f} m"
                )
            level = step.height_m


def terrain_of(steps: Iterable[tuple[float, float]], half_width_m: float) -> Terrain:
    """The terrain of steps given as ``(x_m, height_m)`` pairs in increasing x."""
    return Terrain(steps=tuple(Step(x, h) for x, h in steps), half_width_m=half_width_m)

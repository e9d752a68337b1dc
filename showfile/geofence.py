"""A vehicle's geofence: a convex prism over its board, its home and the transit between (pure).

The fence is the convex hull, in the world x/y plane, of the board's plan-view corners and the
vehicle's home, grown by a horizontal margin; vertically it spans from just below the home's
ground to the cruise height plus a ceiling margin. Every straight move between two points inside
a convex set stays inside it, so a plan whose samples and whose start are inside is inside all the
way, transits and the brush lifts included. It follows from the show file alone, so the agent
that enforces it and the console that draws it build the same one (:func:`show_fence`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from showfile.checks import footprint
from showfile.models import Show
from vehicles import ROOMS

Vec3 = tuple[float, float, float]
Point2 = tuple[float, float]

GROUND_SLACK_M = 0.2
"""How far below the home's height the floor of the fence lies, in [m] (landing gear, noise)."""
_CIRCLE_SIDES = 16
"""The margin around each point is a circumscribed polygon with this many sides."""


class GeofenceError(ValueError):
    """A fence that cannot be built (no area, a bad margin)."""


@dataclass(frozen=True)
class Geofence:
    """A vertical prism: a convex polygon in x/y (counter-clockwise) between two heights."""

    polygon_xy_m: tuple[Point2, ...]
    """Corners in [m], world ENU x/y, counter-clockwise, convex."""
    floor_z_m: float
    """Lowest allowed height in [m], world z."""
    ceiling_z_m: float
    """Highest allowed height in [m], world z."""

    def distance_outside_m(self, p_m_enu: Sequence[float]) -> float:
        """How far in [m] a point lies outside the fence (0 inside or on it; a bound from above
        of the true distance)."""
        x, y, z = float(p_m_enu[0]), float(p_m_enu[1]), float(p_m_enu[2])
        if not all(math.isfinite(v) for v in (x, y, z)):
            return math.inf
        outside_xy = max(self.edge_offset_m(x, y), 0.0)
        outside_z = max(self.floor_z_m - z, z - self.ceiling_z_m, 0.0)
        return math.hypot(outside_xy, outside_z)

    def edge_offset_m(self, x_m: float, y_m: float) -> float:
        """The largest signed distance in [m] of a plan-view point beyond the lines of the
        polygon's edges: positive outside (a bound from above of its distance to the polygon),
        minus its distance to the nearest edge inside."""
        worst = -math.inf
        for x0, y0, ux, uy in self._edges:
            # positive to the right of the edge (outside, for a counter-clockwise polygon)
            offset = ux * (y0 - y_m) - uy * (x0 - x_m)
            if offset > worst:
                worst = offset
        return worst

    @cached_property
    def _edges(self) -> tuple[tuple[float, float, float, float], ...]:
        """Per edge its start and unit direction (x0, y0, ux, uy): built once, since the fence
        is checked at every control tick."""
        poly = self.polygon_xy_m
        edges = []
        for i, (x0, y0) in enumerate(poly):
            x1, y1 = poly[(i + 1) % len(poly)]
            length = math.hypot(x1 - x0, y1 - y0)
            edges.append((x0, y0, (x1 - x0) / length, (y1 - y0) / length))
        return tuple(edges)

    def contains(self, p_m_enu: Sequence[float]) -> bool:
        """Whether a point lies inside (or on) the fence."""
        return self.distance_outside_m(p_m_enu) <= 1e-9

    def first_outside(self, points_m_enu: np.ndarray) -> int | None:
        """Index of the first of (N, 3) points outside the fence, None when all are inside."""
        pts = np.asarray(points_m_enu, dtype=np.float64).reshape(-1, 3)
        if pts.size == 0:
            return None
        outside = ~np.all(np.isfinite(pts), axis=1)
        outside |= (pts[:, 2] < self.floor_z_m - 1e-9) | (pts[:, 2] > self.ceiling_z_m + 1e-9)
        poly = np.asarray(self.polygon_xy_m)
        nxt = np.roll(poly, -1, axis=0)
        edge = nxt - poly
        rel_x = pts[:, None, 0] - poly[None, :, 0]
        rel_y = pts[:, None, 1] - poly[None, :, 1]
        cross = edge[None, :, 0] * rel_y - edge[None, :, 1] * rel_x
        outside |= np.any(cross < -1e-9 * np.hypot(edge[:, 0], edge[:, 1])[None, :], axis=1)
        hits = np.flatnonzero(outside)
        return int(hits[0]) if hits.size else None

    def radius_around_m(self, center_xy_m: Point2) -> float:
        """Largest horizontal distance in [m] from ``center_xy_m`` to a corner of the fence."""
        cx, cy = center_xy_m
        return max(math.hypot(x - cx, y - cy) for x, y in self.polygon_xy_m)


def convex_hull(points: Iterable[Point2]) -> tuple[Point2, ...]:
    """Counter-clockwise convex hull (Andrew's monotone chain), collinear points dropped."""
    pts = sorted(set(points))
    if len(pts) < 3:
        return tuple(pts)

    def cross(o: Point2, a: Point2, b: Point2) -> float:
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    def chain(seq: list[Point2]) -> list[Point2]:
        out: list[Point2] = []
        for p in seq:
            while len(out) >= 2 and cross(out[-2], out[-1], p) <= 0.0:
                out.pop()
            out.append(p)
        return out

    lower, upper = chain(pts), chain(pts[::-1])
    return tuple(lower[:-1] + upper[:-1])


def grown(points: Iterable[Point2], margin_m: float) -> list[Point2]:
    """The points and, around each, a polygon circumscribing a circle of ``margin_m``."""
    out = list(points)
    if margin_m <= 0.0:
        return out
    radius = margin_m / math.cos(math.pi / _CIRCLE_SIDES)
    ring = [
        (radius * math.cos(2 * math.pi * k / _CIRCLE_SIDES),
         radius * math.sin(2 * math.pi * k / _CIRCLE_SIDES))
        for k in range(_CIRCLE_SIDES)
    ]  # fmt: skip
    return [(x + dx, y + dy) for x, y in out for dx, dy in ring]


def vehicle_fence(
    board_corners_xy_m: Sequence[Point2],
    home_m_enu: Vec3,
    cruise_z_m: float,
    *,
    margin_m: float,
    ceiling_margin_m: float,
) -> Geofence:
    """The fence of a vehicle: hull of its board's corners and its home grown by ``margin_m``,
    from below the home's ground to ``cruise_z_m + ceiling_margin_m``."""
    if margin_m < 0.0 or ceiling_margin_m < 0.0:
        raise GeofenceError(f"fence margins must be >= 0, got {margin_m}, {ceiling_margin_m}")
    points = [*((float(x), float(y)) for x, y in board_corners_xy_m), home_m_enu[:2]]
    hull = fence_outline_xy_m(points, margin_m)
    if len(hull) < 3:
        raise GeofenceError("the fence has no area: give the board a size or a margin > 0")
    floor = float(home_m_enu[2]) - GROUND_SLACK_M
    ceiling = float(cruise_z_m) + ceiling_margin_m
    if ceiling <= floor:
        raise GeofenceError(f"fence ceiling {ceiling:.2f} m is not above its floor {floor:.2f} m")
    return Geofence(hull, floor, ceiling)


def fence_outline_xy_m(points_xy_m: Iterable[Point2], margin_m: float) -> tuple[Point2, ...]:
    """The plan view of a fence: the convex hull of ``points_xy_m`` grown by ``margin_m``,
    counter-clockwise, in [m] world x/y."""
    return convex_hull(grown(points_xy_m, margin_m))


def show_fence(show: Show, vehicle_id: str, cruise_z_m: float) -> Geofence:
    """The show's fence of one vehicle: its board, its home and the transit between them (for a
    kind whose transit goes ``sideways_first``, the corners of its legs too), up to
    ``cruise_z_m`` plus the ceiling margin of the show's ``safety`` section."""
    vehicle = show.vehicle(vehicle_id)
    return vehicle_fence(
        _transit_corners_xy_m(show, vehicle_id),
        vehicle.home_m_enu,
        cruise_z_m,
        margin_m=show.safety.fence_margin_m,
        ceiling_margin_m=show.safety.fence_ceiling_margin_m,
    )


def show_fence_outline_xy_m(show: Show, vehicle_id: str) -> tuple[Point2, ...]:
    """The plan view of :func:`show_fence` (what the console draws), in [m] world x/y."""
    home = show.vehicle(vehicle_id).home_m_enu
    points = [*_transit_corners_xy_m(show, vehicle_id), (home[0], home[1])]
    return fence_outline_xy_m(points, show.safety.fence_margin_m)


def _transit_corners_xy_m(show: Show, vehicle_id: str) -> list[Point2]:
    """The board's plan-view corners and, for a ``sideways_first`` kind, its legs' corners."""
    vehicle = show.vehicle(vehicle_id)
    corners = footprint(show.board(vehicle.board))
    if ROOMS[vehicle.kind].transit_route == "sideways_first":
        hx, hy = vehicle.home_m_enu[0], vehicle.home_m_enu[1]
        corners += [(hx, y) for _, y in corners] + [(x, hy) for x, _ in corners]
    return corners

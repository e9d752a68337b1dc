"""The fixed part of the scene: boards, walls, floor areas with their writing areas, homes and
geofences, each an entity in the world frame (``venue/<kind>/<id>``)."""

from __future__ import annotations

import math

import foxglove.messages as fg

from scene.encode import WORLD_FRAME, colour, point, pose, timestamp, vector
from showfile import Board, Show
from showfile.geofence import show_fence_outline_xy_m

SURFACE_THICKNESS_M = 0.02
"""Drawn thickness in [m] of a board, a wall panel or a floor area."""
HOME_DIAMETER_M = 0.3
"""Drawn diameter in [m] of a home pad."""
SURFACE_COLOURS = {"horizontal": "#f2f2f2", "vertical": "#d9d9d9", "floor": "#b08d57"}
AREA_COLOUR, HOME_COLOUR, FENCE_COLOUR, LABEL_COLOUR = "#0087ff", "#00af00", "#ffd700", "#ffffff"


def venue_update(show: Show, stamp_ns: int) -> fg.SceneUpdate:
    """Every board, home and geofence of ``show`` (sent again now and then, so a recording
    opened at any point shows them)."""
    entities = [_board(board, stamp_ns) for board in show.boards]
    for vehicle in show.vehicles:
        home = vehicle.home_m_enu
        entities.append(
            fg.SceneEntity(
                timestamp=timestamp(stamp_ns),
                frame_id=WORLD_FRAME,
                id=f"venue/home/{vehicle.id}",
                cylinders=[
                    fg.CylinderPrimitive(
                        pose=pose((home[0], home[1], home[2] + 0.005)),
                        size=fg.Vector3(x=HOME_DIAMETER_M, y=HOME_DIAMETER_M, z=0.01),
                        bottom_scale=1.0,
                        top_scale=1.0,
                        color=colour(HOME_COLOUR, 0.8),
                    )
                ],
                texts=[_label(f"home {vehicle.id}", (home[0], home[1], home[2] + 0.1))],
            )
        )
        outline = show_fence_outline_xy_m(show, vehicle.id)
        entities.append(
            fg.SceneEntity(
                timestamp=timestamp(stamp_ns),
                frame_id=WORLD_FRAME,
                id=f"venue/fence/{vehicle.id}",
                lines=[
                    fg.LinePrimitive(
                        type=fg.LinePrimitiveLineType.LineLoop,
                        pose=pose((0.0, 0.0, 0.0)),
                        thickness=2.0,
                        scale_invariant=True,
                        points=[point((x, y, home[2])) for x, y in outline],
                        color=colour(FENCE_COLOUR, 0.8),
                    )
                ],
            )
        )
    return fg.SceneUpdate(entities=entities)


def _board(board: Board, stamp_ns: int) -> fg.SceneEntity:
    """A board as a slab whose face is its writing surface, the writing area outlined on it."""
    width_m, height_m = board.size_m
    half_w_m, half_h_m = board.writing_area_m[0] / 2, board.writing_area_m[1] / 2
    t = SURFACE_THICKNESS_M
    cx, cy, cz = board.center_m_enu
    c, s = math.cos(board.yaw_rad), math.sin(board.yaw_rad)
    if board.orientation == "vertical":  # a wall panel: x along the board, z up, behind its face
        size = (width_m, t, height_m)
        slab = (cx - s * t / 2, cy + c * t / 2, cz)
        corners = [(-half_w_m, 0.0, -half_h_m), (half_w_m, 0.0, -half_h_m)]
        corners += [(half_w_m, 0.0, half_h_m), (-half_w_m, 0.0, half_h_m)]
        label_z_m = cz + height_m / 2 + 0.1
    else:  # a table or a floor area: its top is the writing surface
        size = (width_m, height_m, t)
        slab = (cx, cy, cz - t / 2)
        corners = [(-half_w_m, -half_h_m, 0.0), (half_w_m, -half_h_m, 0.0)]
        corners += [(half_w_m, half_h_m, 0.0), (-half_w_m, half_h_m, 0.0)]
        label_z_m = cz + 0.1
    return fg.SceneEntity(
        timestamp=timestamp(stamp_ns),
        frame_id=WORLD_FRAME,
        id=f"venue/board/{board.id}",
        cubes=[
            fg.CubePrimitive(
                pose=pose(slab, board.yaw_rad),
                size=vector(size),
                color=colour(SURFACE_COLOURS.get(board.orientation, "#f2f2f2"), 0.9),
            )
        ],
        lines=[
            fg.LinePrimitive(
                type=fg.LinePrimitiveLineType.LineLoop,
                pose=pose((cx, cy, cz + 0.001), board.yaw_rad),
                thickness=1.5,
                scale_invariant=True,
                points=[point(corner) for corner in corners],
                color=colour(AREA_COLOUR, 0.8),
            )
        ],
        texts=[_label(board.id, (cx, cy, label_z_m))],
    )


def _label(text: str, at: tuple[float, float, float]) -> fg.TextPrimitive:
    return fg.TextPrimitive(
        pose=pose(at),
        billboard=True,
        font_size=14.0,
        scale_invariant=True,
        color=colour(LABEL_COLOUR),
        text=text,
    )

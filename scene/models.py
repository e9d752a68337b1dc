"""A model of each vehicle, drawn in its own frame (``frame_locked``): it moves and tilts with
the frame that ``/tf`` gives it (``scene.vehicles.transforms``).

A vehicle's frame has its origin at the vehicle's reference point (``Telemetry.position_m_enu``,
where its tracking error is measured) and the body's axes, forward-left-up. That point is the
body's centre for the brush quadrotor, and the writing point itself for the wall hexarotor (its
sponge) and the omni-wheel vehicle (its marker): their bodies are drawn behind it. The scene may
not import the rooms (they pull in the planner), so their few dimensions are copied here, each
with where it comes from; ``tests/test_scene_frames.py`` holds them to the rooms.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import foxglove.messages as fg

from scene.encode import colour, pose, timestamp, vector
from showfile import Show

Point = tuple[float, float, float]
MODEL_COLOUR, ROTOR_COLOUR, TOOL_COLOUR = "#ff5f00", "#5f5f5f", "#101010"


@dataclass(frozen=True)
class Model:
    """How one kind is drawn in its vehicle's frame, in [m]."""

    body_centre_m: Point
    """Centre of the body's box."""
    body_size_m: Point
    """The body's box: length, width, height."""
    rotors: tuple[int, float, float] | None = None
    """Rotors, their distance from the body's centre and their disc diameter (None: no rotor)."""
    tool_centre_m: Point | None = None
    """Centre of the box drawn for what holds the pen (brush shaft, arm), if drawn."""
    tool_size_m: Point = (0.0, 0.0, 0.0)


BRUSH_LENGTH_M = 0.35
"""Reference point to brush tip in [m], fully extended
(``vehicles.quadrotor_brush.params.BrushParams.length_m``)."""
SPONGE_TIP_M_BODY = 0.52
"""Body centre to the sponge's tip along body x in [m]: the arm's base 0.12 m out plus the arm's
0.40 m (``vehicles.hexarotor_sponge.params.HexarotorParams.tip_m_body``)."""
MARKER_M_BODY = (0.1575, 0.0, -0.066)
"""The marker in the omni-wheel vehicle's rear part's frame (middle axle, at axle height): free
joint 1 at 0.060 m plus half the 0.195 m front link, on the floor one wheel radius below
(``vehicles.omni_wheel.geometry.OmniGeometry``, ``model.py``'s ``pen`` site)."""
OMNI_LENGTH_M = 0.66
"""Length in [m]: tail (0.34 m behind the middle axle) to the front wheels' rims (0.32 m
ahead of it)."""

MODELS = {
    "quadrotor-brush": Model(
        body_centre_m=(0.0, 0.0, 0.0),
        body_size_m=(0.18, 0.18, 0.06),
        rotors=(4, 0.20, 0.25),  # Airshow: 40 cm motor to motor, 10-inch propellers
        tool_centre_m=(0.0, 0.0, -BRUSH_LENGTH_M / 2),
        tool_size_m=(0.01, 0.01, BRUSH_LENGTH_M),
    ),
    "hexarotor-sponge": Model(
        body_centre_m=(-SPONGE_TIP_M_BODY, 0.0, 0.0),
        body_size_m=(0.18, 0.18, 0.06),
        rotors=(6, 0.28, 0.20),  # the Flying Calligrapher's rotors 0.28 m out
        tool_centre_m=(-0.20, 0.0, 0.0),  # the 0.40 m arm, its base 0.12 m ahead of the centre
        tool_size_m=(0.40, 0.02, 0.02),
    ),
    "omni-wheel": Model(
        body_centre_m=(-MARKER_M_BODY[0] - 0.01, 0.0, 0.125),
        body_size_m=(OMNI_LENGTH_M, 0.42, 0.25),  # 0.30 m track plus the wheels
    ),
}
"""Kind -> its model; a kind not named here is drawn as a box at its reference point."""
DEFAULT_MODEL = Model(body_centre_m=(0.0, 0.0, 0.0), body_size_m=(0.3, 0.3, 0.15))


def vehicle_models(show: Show, stamp_ns: int) -> fg.SceneUpdate:
    """A model of each vehicle in its own frame (``frame_locked``: it moves with the frame)."""
    return fg.SceneUpdate(entities=[_entity(v.id, v.kind, stamp_ns) for v in show.vehicles])


def _entity(vehicle_id: str, kind: str, stamp_ns: int) -> fg.SceneEntity:
    model = MODELS.get(kind, DEFAULT_MODEL)
    cx, cy, cz = model.body_centre_m
    cubes = [
        fg.CubePrimitive(
            pose=pose(model.body_centre_m),
            size=vector(model.body_size_m),
            color=colour(MODEL_COLOUR),
        )
    ]
    if model.tool_centre_m is not None:
        cubes.append(
            fg.CubePrimitive(
                pose=pose(model.tool_centre_m),
                size=vector(model.tool_size_m),
                color=colour(TOOL_COLOUR),
            )
        )
    return fg.SceneEntity(
        timestamp=timestamp(stamp_ns),
        frame_id=vehicle_id,
        id=f"vehicle/{vehicle_id}",
        frame_locked=True,
        metadata=[fg.KeyValuePair(key="kind", value=kind)],
        cubes=cubes,
        cylinders=_rotors(model),
        texts=[
            fg.TextPrimitive(
                pose=pose((cx, cy, cz + 0.35)),
                billboard=True,
                font_size=14.0,
                scale_invariant=True,
                color=colour("#ffffff"),
                text=vehicle_id,
            )
        ],
    )


def _rotors(model: Model) -> list[fg.CylinderPrimitive]:
    if model.rotors is None:
        return []
    count, arm_m, diameter_m = model.rotors
    cx, cy, cz = model.body_centre_m
    return [
        fg.CylinderPrimitive(
            pose=pose((cx + arm_m * math.cos(a), cy + arm_m * math.sin(a), cz + 0.04)),
            size=fg.Vector3(x=diameter_m, y=diameter_m, z=0.01),
            bottom_scale=1.0,
            top_scale=1.0,
            color=colour(ROTOR_COLOUR, 0.6),
        )
        for a in (2 * math.pi * (i + 0.5) / count for i in range(count))
    ]

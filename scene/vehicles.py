"""The moving part of the scene: each vehicle's frame (``foxglove.FrameTransforms``), a model of
it drawn in that frame, its planned and flown paths and its ink as laid down."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import foxglove.messages as fg

from bus.messages import Telemetry
from scene.encode import WORLD_FRAME, colour, point, pose, timestamp, vector
from showfile import Show

Point = tuple[float, float, float]
MAX_PATH_POINTS = 6_000
"""Points kept per line of one job (5 min of telemetry at 20 Hz); past it every other one goes."""
PLANNED_COLOUR, FLOWN_COLOUR, INK_COLOUR, MODEL_COLOUR = "#0087ff", "#8a8a8a", "#101010", "#ff5f00"


def setpoint_frame(vehicle_id: str) -> str:
    """The frame of where the vehicle should be now (its reference), child of the world."""
    return f"{vehicle_id}/setpoint"


def transforms(t: Telemetry, stamp_ns: int) -> fg.FrameTransforms:
    """World -> the vehicle's tracked point (its frame, named by its id) and -> its setpoint.
    Telemetry carries no attitude: the frames keep the world's axes."""
    identity = fg.Quaternion(x=0.0, y=0.0, z=0.0, w=1.0)
    frames = [
        fg.FrameTransform(
            timestamp=timestamp(stamp_ns),
            parent_frame_id=WORLD_FRAME,
            child_frame_id=t.vehicle_id,
            translation=vector(t.position_m_enu),
            rotation=identity,
        )
    ]
    if t.reference_m_enu is not None:
        frames.append(
            fg.FrameTransform(
                timestamp=timestamp(stamp_ns),
                parent_frame_id=WORLD_FRAME,
                child_frame_id=setpoint_frame(t.vehicle_id),
                translation=vector(t.reference_m_enu),
                rotation=identity,
            )
        )
    return fg.FrameTransforms(transforms=frames)


def vehicle_models(show: Show, stamp_ns: int) -> fg.SceneUpdate:
    """A model of each vehicle in its own frame (``frame_locked``: it moves with the frame)."""
    entities = []
    for vehicle in show.vehicles:
        entities.append(
            fg.SceneEntity(
                timestamp=timestamp(stamp_ns),
                frame_id=vehicle.id,
                id=f"vehicle/{vehicle.id}",
                frame_locked=True,
                metadata=[fg.KeyValuePair(key="kind", value=vehicle.kind)],
                cubes=[_body(vehicle.kind)],
                cylinders=_rotors(vehicle.kind),
                texts=[
                    fg.TextPrimitive(
                        pose=pose((0.0, 0.0, 0.35)),
                        billboard=True,
                        font_size=14.0,
                        scale_invariant=True,
                        color=colour("#ffffff"),
                        text=vehicle.id,
                    )
                ],
            )
        )
    return fg.SceneUpdate(entities=entities)


ROTORS = {"quadrotor-brush": (4, 0.20, 0.25), "hexarotor-sponge": (6, 0.28, 0.20)}
"""Per multirotor kind: rotors, their distance from the centre and their disc diameter, in [m]
(the Airshow quadrotor: 40 cm motor to motor, 10-inch propellers; the Flying Calligrapher's
rotors 0.28 m out, as in ``vehicles.ROOMS``' footprints)."""


def _body(kind: str) -> fg.CubePrimitive:
    size = (0.6, 0.5, 0.25) if kind not in ROTORS else (0.18, 0.18, 0.06)
    return fg.CubePrimitive(
        pose=pose((0.0, 0.0, 0.0)), size=vector(size), color=colour(MODEL_COLOUR)
    )


def _rotors(kind: str) -> list[fg.CylinderPrimitive]:
    if kind not in ROTORS:
        return []
    count, arm_m, diameter_m = ROTORS[kind]
    return [
        fg.CylinderPrimitive(
            pose=pose((arm_m * math.cos(a), arm_m * math.sin(a), 0.04)),
            size=fg.Vector3(x=diameter_m, y=diameter_m, z=0.01),
            bottom_scale=1.0,
            top_scale=1.0,
            color=colour("#5f5f5f", 0.6),
        )
        for a in (2 * math.pi * (i + 0.5) / count for i in range(count))
    ]


@dataclass
class JobPaths:
    """One vehicle's current job: the reference flown so far, the flight, the ink."""

    job_id: str | None = None
    planned: list[Point] = field(default_factory=list)
    flown: list[Point] = field(default_factory=list)
    ink: list[Point] = field(default_factory=list)
    """Pairs of points: each segment flown with the pen down."""
    _last_down: Point | None = None

    def add(self, t: Telemetry) -> None:
        """Take one telemetry sample (a new job starts the paths afresh)."""
        if t.job_id != self.job_id:
            self.job_id, self.planned, self.flown, self.ink = t.job_id, [], [], []
            self._last_down = None
        if t.job_id is None:
            return
        if t.reference_m_enu is not None:
            self.planned.append(t.reference_m_enu)
        self.flown.append(t.position_m_enu)
        if t.pen_down and self._last_down is not None:
            self.ink += [self._last_down, t.position_m_enu]
        self._last_down = t.position_m_enu if t.pen_down else None
        for name in ("planned", "flown", "ink"):
            points = getattr(self, name)
            if len(points) > MAX_PATH_POINTS:
                keep = (
                    points[::2] if name != "ink" else [p for i, p in enumerate(points) if i % 4 < 2]
                )
                setattr(self, name, keep)

    def entity(self, vehicle_id: str, stamp_ns: int) -> fg.SceneEntity:
        lines = [
            _line(fg.LinePrimitiveLineType.LineStrip, self.planned, PLANNED_COLOUR, 1.5),
            _line(fg.LinePrimitiveLineType.LineStrip, self.flown, FLOWN_COLOUR, 1.0),
            _line(fg.LinePrimitiveLineType.LineList, self.ink, INK_COLOUR, 4.0),
        ]
        return fg.SceneEntity(
            timestamp=timestamp(stamp_ns),
            frame_id=WORLD_FRAME,
            id=f"path/{vehicle_id}",
            metadata=[fg.KeyValuePair(key="job", value=self.job_id or "")],
            lines=[line for line in lines if line is not None],
        )


def _line(
    kind: fg.LinePrimitiveLineType,
    points: list[Point],
    hex_rgb: str,
    px: float,
) -> fg.LinePrimitive | None:
    if len(points) < 2:
        return None
    return fg.LinePrimitive(
        type=kind,
        pose=pose((0.0, 0.0, 0.0)),
        thickness=px,
        scale_invariant=True,
        points=[point(p) for p in points],
        color=colour(hex_rgb),
    )

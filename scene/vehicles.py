"""The moving part of the scene: each vehicle's frames (``foxglove.FrameTransforms``), its
planned and flown paths and its ink as laid down (its model: ``scene.models``)."""

from __future__ import annotations

from dataclasses import dataclass, field

import foxglove.messages as fg

from bus.messages import Telemetry
from scene.encode import (
    IDENTITY,
    WORLD_FRAME,
    colour,
    point,
    pose,
    quaternion,
    rotated_back,
    timestamp,
    unit,
    vector,
)

Point = tuple[float, float, float]
MAX_PATH_POINTS = 6_000
"""Points kept per line of one job (5 min of telemetry at 20 Hz); past it every other one goes."""
PLANNED_COLOUR, FLOWN_COLOUR, INK_COLOUR = "#0087ff", "#8a8a8a", "#101010"


def setpoint_frame(vehicle_id: str) -> str:
    """The frame of where the vehicle should be now (its reference), child of the world."""
    return f"{vehicle_id}/setpoint"


def writing_point_frame(vehicle_id: str) -> str:
    """The frame of the vehicle's writing point (brush tip, sponge, marker), child of the
    vehicle's frame."""
    return f"{vehicle_id}/writing_point"


def transforms(t: Telemetry, stamp_ns: int) -> fg.FrameTransforms:
    """World -> the vehicle's frame (named by its id: its reference point, turned as its body),
    the vehicle's frame -> its writing point, and world -> its setpoint (world axes).

    The writing point is a child of the vehicle, as a tool frame hangs below ``base_link`` in
    ROS: its offset is the brush's or the arm's in body axes (nearly constant), so a frame
    interpolated between two samples stays on the drawn vehicle, and its axes are the body's.
    Telemetry without attitude (an older agent, a vehicle at rest) keeps the world's axes;
    without a writing point there is no writing-point frame."""
    attitude = IDENTITY if t.attitude_xyzw_enu is None else unit(t.attitude_xyzw_enu)
    stamp = timestamp(stamp_ns)
    frames = [
        fg.FrameTransform(
            timestamp=stamp,
            parent_frame_id=WORLD_FRAME,
            child_frame_id=t.vehicle_id,
            translation=vector(t.position_m_enu),
            rotation=quaternion(attitude),
        )
    ]
    if t.writing_point_m_enu is not None:
        (wx, wy, wz), (px, py, pz) = t.writing_point_m_enu, t.position_m_enu
        frames.append(
            fg.FrameTransform(
                timestamp=stamp,
                parent_frame_id=t.vehicle_id,
                child_frame_id=writing_point_frame(t.vehicle_id),
                translation=vector(rotated_back(attitude, (wx - px, wy - py, wz - pz))),
                rotation=quaternion(IDENTITY),
            )
        )
    if t.reference_m_enu is not None:
        frames.append(
            fg.FrameTransform(
                timestamp=stamp,
                parent_frame_id=WORLD_FRAME,
                child_frame_id=setpoint_frame(t.vehicle_id),
                translation=vector(t.reference_m_enu),
                rotation=quaternion(IDENTITY),
            )
        )
    return fg.FrameTransforms(transforms=frames)


@dataclass
class JobPaths:
    """One vehicle's current job: the reference flown so far, the flight, the ink."""

    job_id: str | None = None
    planned: list[Point] = field(default_factory=list)
    """The reference of the vehicle's reference point, sample by sample."""
    flown: list[Point] = field(default_factory=list)
    """Where the reference point went: the line to hold against ``planned``."""
    ink: list[Point] = field(default_factory=list)
    """Pairs of points: each segment the writing point moved with the pen down (the reference
    point where telemetry has no writing point: an older agent, an old recording)."""
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
        pen = t.writing_point_m_enu if t.writing_point_m_enu is not None else t.position_m_enu
        if t.pen_down and self._last_down is not None:
            self.ink += [self._last_down, pen]
        self._last_down = pen if t.pen_down else None
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

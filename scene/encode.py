"""Foxglove messages encoded for an MCAP channel or a WebSocket channel: the schema the SDK ships
(protobuf) or, for plot series, a JSON schema of our own."""

from __future__ import annotations

import json
import math
from typing import Any, Protocol

import foxglove.messages as fg

from bus.recorder import DerivedMessage

WORLD_FRAME = "world"
"""The show's world frame: x east, y north, z up, in [m] (the show file's ENU)."""


class FoxgloveMessage(Protocol):
    def encode(self) -> bytes: ...

    @staticmethod
    def get_schema() -> Any: ...


def encoded(topic: str, message: FoxgloveMessage) -> DerivedMessage:
    """``message`` on ``topic`` in its Foxglove schema, protobuf-encoded as the SDK does."""
    schema = message.get_schema()
    return DerivedMessage(
        topic=topic,
        schema_name=schema.name,
        schema_encoding=schema.encoding,
        schema_data=bytes(schema.data),
        message_encoding=schema.encoding,
        payload=message.encode(),
    )


def json_encoded(topic: str, name: str, schema: dict[str, Any], value: Any) -> DerivedMessage:
    """A JSON message with its JSON schema (plot series: Foxglove plots any numeric field)."""
    return DerivedMessage(
        topic=topic,
        schema_name=name,
        schema_encoding="jsonschema",
        schema_data=json.dumps(schema, sort_keys=True).encode(),
        message_encoding="json",
        payload=json.dumps(value, separators=(",", ":")).encode(),
    )


def timestamp(stamp_ns: int) -> fg.Timestamp:
    return fg.Timestamp(stamp_ns // 1_000_000_000, stamp_ns % 1_000_000_000)


def vector(v: tuple[float, float, float] | Any) -> fg.Vector3:
    return fg.Vector3(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def point(v: tuple[float, float, float] | Any) -> fg.Point3:
    return fg.Point3(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def yaw_quaternion(yaw_rad: float) -> fg.Quaternion:
    """A rotation about up by ``yaw_rad``."""
    return fg.Quaternion(x=0.0, y=0.0, z=math.sin(yaw_rad / 2), w=math.cos(yaw_rad / 2))


def pose(position: tuple[float, float, float], yaw_rad: float = 0.0) -> fg.Pose:
    return fg.Pose(position=vector(position), orientation=yaw_quaternion(yaw_rad))


def colour(hex_rgb: str, alpha: float = 1.0) -> fg.Color:
    """``#rrggbb`` as a Foxglove colour."""
    value = int(hex_rgb.lstrip("#"), 16)
    return fg.Color(
        r=(value >> 16) / 255.0, g=((value >> 8) & 0xFF) / 255.0, b=(value & 0xFF) / 255.0, a=alpha
    )

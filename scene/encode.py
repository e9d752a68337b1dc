"""Foxglove messages encoded for an MCAP channel or a WebSocket channel: the schema the SDK ships
(protobuf) or, for plot series, a JSON schema of our own."""

from __future__ import annotations

import json
import math
from typing import Any, Protocol

import foxglove.messages as fg

from bus.mcap_channels import DerivedMessage

WORLD_FRAME = "world"
"""The show's world frame: x east, y north, z up, in [m] (the show file's ENU)."""


class FoxgloveMessage(Protocol):
    def encode(self) -> bytes: ...

    @staticmethod
    def get_schema() -> Any: ...


def encoded(topic: str, message: FoxgloveMessage) -> DerivedMessage:
    """``message`` on ``topic`` in its Foxglove schema, protobuf-encoded as the SDK does."""
    return declared(topic, type(message), message.encode())


def declared(
    topic: str, message_type: type[FoxgloveMessage], payload: bytes = b""
) -> DerivedMessage:
    """``topic``'s channel for ``message_type`` in its Foxglove schema, carrying ``payload``
    (empty: no message, what a channel is opened from before anything is sent on it)."""
    schema = message_type.get_schema()
    return DerivedMessage(
        topic=topic,
        schema_name=schema.name,
        schema_encoding=schema.encoding,
        schema_data=bytes(schema.data),
        message_encoding=schema.encoding,
        payload=payload,
    )


def json_encoded(topic: str, name: str, schema: dict[str, Any], value: Any) -> DerivedMessage:
    """A JSON message with its JSON schema (plot series: Foxglove plots any numeric field)."""
    return json_declared(topic, name, schema, json.dumps(value, separators=(",", ":")).encode())


def json_declared(
    topic: str, name: str, schema: dict[str, Any], payload: bytes = b""
) -> DerivedMessage:
    """``topic``'s channel for JSON messages of ``schema`` named ``name``, carrying ``payload``
    (empty: no message, as :func:`declared`)."""
    return DerivedMessage(
        topic=topic,
        schema_name=name,
        schema_encoding="jsonschema",
        schema_data=json.dumps(schema, sort_keys=True).encode(),
        message_encoding="json",
        payload=payload,
    )


def timestamp(stamp_ns: int) -> fg.Timestamp:
    return fg.Timestamp(stamp_ns // 1_000_000_000, stamp_ns % 1_000_000_000)


def vector(v: tuple[float, float, float] | Any) -> fg.Vector3:
    return fg.Vector3(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def point(v: tuple[float, float, float] | Any) -> fg.Point3:
    return fg.Point3(x=float(v[0]), y=float(v[1]), z=float(v[2]))


Quaternion = tuple[float, float, float, float]
"""A quaternion (x, y, z, w), as ``Telemetry.attitude_xyzw_enu``."""
IDENTITY: Quaternion = (0.0, 0.0, 0.0, 1.0)


UNIT_TOLERANCE = 1e-9
"""A quaternion whose length is this close to 1 is sent as it came, bit for bit."""


def unit(q: Quaternion) -> Quaternion:
    """``q`` scaled to length 1 (the identity for a zero one)."""
    n = math.sqrt(sum(c * c for c in q))
    if abs(n - 1.0) <= UNIT_TOLERANCE:
        return q
    return IDENTITY if n == 0.0 else (q[0] / n, q[1] / n, q[2] / n, q[3] / n)


def quaternion(q: Quaternion) -> fg.Quaternion:
    return fg.Quaternion(x=float(q[0]), y=float(q[1]), z=float(q[2]), w=float(q[3]))


def rotated_back(q: Quaternion, v: tuple[float, float, float]) -> tuple[float, float, float]:
    """``v`` (world axes) in the axes of a body turned by the unit quaternion ``q``: ``R(q)^T v``
    (``v + 2w (u x v) + 2 u x (u x v)`` with ``u = -(x, y, z)``, the conjugate's vector part)."""
    ux, uy, uz, w = -q[0], -q[1], -q[2], q[3]
    cx, cy, cz = uy * v[2] - uz * v[1], uz * v[0] - ux * v[2], ux * v[1] - uy * v[0]
    dx, dy, dz = uy * cz - uz * cy, uz * cx - ux * cz, ux * cy - uy * cx
    return (
        v[0] + 2 * (w * cx + dx),
        v[1] + 2 * (w * cy + dy),
        v[2] + 2 * (w * cz + dz),
    )


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

"""Telemetry's wire format as docs/protocol.md tells it: every field is named in its paragraph,
and the v1 additions (attitude, writing point) are optional both ways (issue 36)."""

from __future__ import annotations

import re
from pathlib import Path

import msgspec

from bus.messages import Telemetry

PROTOCOL_MD = Path(__file__).resolve().parents[1] / "docs" / "protocol.md"


def test_every_telemetry_field_is_documented() -> None:
    text = PROTOCOL_MD.read_text(encoding="utf-8")
    paragraph = text.split("**Telemetry** (20 Hz):", 1)[1].split("\n\n", 1)[0]
    documented = set(re.findall(r"`([a-z_]+)`", paragraph))
    fields = {f.encode_name for f in msgspec.structs.fields(Telemetry)}
    assert fields - {"v"} <= documented, fields - documented


class OlderTelemetry(msgspec.Struct, frozen=True):
    """A reader of v1 before the attitude and the writing point (its fields, in part)."""

    vehicle_id: str
    position_m_enu: tuple[float, float, float]


def test_attitude_and_writing_point_are_optional_both_ways() -> None:
    newer = Telemetry(
        vehicle_id="uav1", t_s=1.0, state="writing", position_m_enu=(1.0, 2.0, 3.0),
        velocity_mps_enu=(0.0, 0.0, 0.0), attitude_xyzw_enu=(0.0, 0.0, 0.6, 0.8),
        writing_point_m_enu=(1.0, 2.0, 2.65),
    )  # fmt: skip
    raw = msgspec.json.encode(newer)
    assert msgspec.json.decode(raw, type=Telemetry) == newer
    assert msgspec.json.decode(raw, type=OlderTelemetry).position_m_enu == (1.0, 2.0, 3.0)
    older = msgspec.json.encode(OlderTelemetry("uav1", (1.0, 2.0, 3.0)))
    sample = msgspec.json.decode(
        older[:-1] + b',"t_s":1,"state":"idle","velocity_mps_enu":[0,0,0]}', type=Telemetry
    )
    assert sample.attitude_xyzw_enu is None and sample.writing_point_m_enu is None

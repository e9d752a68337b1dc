"""The show's recording carries a 3D scene in Foxglove's schemas beside the bus's own channels,
and every channel of it decodes and validates against the schema it carries (issue 36)."""

from __future__ import annotations

import math
from pathlib import Path

import msgspec
from mcap.reader import make_reader
from scene_decode import decoded

from bus.keys import ShowKeys
from bus.messages import Event, Telemetry
from bus.recorder import McapRecorder
from scene.show_scene import LOG_TOPIC, PATHS_TOPIC, TF_TOPIC, VENUE_TOPIC, ShowScene
from showfile import load_show

SHOW = load_show("shows/mixed.yaml")
KEYS = ShowKeys(SHOW.show_id)
T0_NS = 1_900_000_000 * 10**9


def _circle(vehicle_id: str, i: int) -> Telemetry:
    """uav1 writes a circle of 0.3 m on b1: pen down for samples 10-49, up otherwise."""
    a = 2 * math.pi * i / 40
    board = SHOW.board("b1").center_m_enu
    position = (board[0] + 0.3 * math.cos(a), board[1] + 0.3 * math.sin(a), board[2])
    return Telemetry(
        vehicle_id=vehicle_id,
        t_s=i * 0.05,
        state="writing",
        position_m_enu=position,
        velocity_mps_enu=(0.0, 0.0, 0.0),
        reference_m_enu=(position[0] + 0.01, position[1], position[2]),
        pen_down=10 <= i < 50,
        tracking_error_m=0.01,
        job_id="j1",
        progress=i / 60,
    )


def _record(path: Path) -> McapRecorder:
    scene = ShowScene(SHOW)
    with McapRecorder(path, KEYS, derive=scene.derive) as recorder:
        for i in range(60):
            sample = _circle("uav1", i)
            recorder.record(
                KEYS.telemetry("uav1"), msgspec.json.encode(sample), time_ns=T0_NS + i * 50_000_000
            )
        event = Event(
            time_s=3.0, level="alert", kind="limit", message="uav1 5 cm off", vehicle_id="uav1"
        )
        recorder.record(KEYS.events, msgspec.json.encode(event), time_ns=T0_NS + 3_100_000_000)
    return recorder


def test_every_channel_decodes_with_its_schema_and_the_scene_is_the_show(tmp_path: Path) -> None:
    path = tmp_path / "show.mcap"
    recorder = _record(path)
    assert recorder.derive_failures == 0
    by_topic: dict[str, list[object]] = {}
    with path.open("rb") as f:
        for schema, channel, message in make_reader(f).iter_messages():
            assert schema is not None
            value = decoded(channel.message_encoding, schema.name, schema.data, message.data)
            by_topic.setdefault(channel.topic, []).append(value)
            if channel.topic.startswith("/"):
                assert schema.name.startswith(("foxglove.", "skyquill.")), schema.name
    assert {TF_TOPIC, VENUE_TOPIC, PATHS_TOPIC, LOG_TOPIC, "/plot"} <= by_topic.keys()

    venue = by_topic[VENUE_TOPIC][0]
    ids = {e.id for e in venue.entities}  # type: ignore[attr-defined]
    assert {f"venue/board/{b.id}" for b in SHOW.boards} <= ids
    assert {f"venue/fence/{v.id}" for v in SHOW.vehicles} <= ids

    transforms = by_topic[TF_TOPIC]
    assert len(transforms) == 60
    last = _circle("uav1", 59)
    frame = transforms[-1].transforms[0]  # type: ignore[attr-defined]
    assert (frame.parent_frame_id, frame.child_frame_id) == ("world", "uav1")
    got = (frame.translation.x, frame.translation.y, frame.translation.z)
    assert got == last.position_m_enu

    paths = by_topic[PATHS_TOPIC][-1].entities[0]  # type: ignore[attr-defined]
    ink = next(line for line in paths.lines if line.type == 2)  # LINE_LIST
    assert len(ink.points) == 2 * 39  # pen down for samples 10-49: 39 segments by sample 50
    planned = next(line for line in paths.lines if line.color.b > 0.9)
    assert len(by_topic[PATHS_TOPIC]) == 6  # every 0.5 s of 3 s: samples 0, 10, ..., 50
    assert len(planned.points) == 51

    log = by_topic[LOG_TOPIC][0]
    assert log.message == "uav1 5 cm off" and log.level == 4  # ERROR  # type: ignore[attr-defined]
    plot = by_topic["/plot"][20]
    assert plot == {
        "vehicle_id": "uav1",
        "tracking_error_m": 0.01, "force_n": None, "force_reference_n": None,
        "pen_down": True, "progress": 20 / 60,
    }  # fmt: skip


def test_a_scene_that_cannot_be_drawn_never_stops_the_recording(tmp_path: Path) -> None:
    def broken(topic: str, payload: bytes, stamp_ns: int) -> list[object]:
        raise ValueError("no scene")

    with McapRecorder(tmp_path / "r.mcap", KEYS, derive=broken) as recorder:  # type: ignore[arg-type]
        for i in range(5):
            recorder.record(KEYS.telemetry("uav1"), msgspec.json.encode(_circle("uav1", i)))
    assert recorder.derive_failures == 5 and recorder.messages == 5


def test_the_scene_is_handed_each_message_decoded_once_as_its_topics_type(tmp_path: Path) -> None:
    handed: list[tuple[str, object]] = []

    def derive(topic: str, message: msgspec.Struct | None, stamp_ns: int) -> list[object]:
        handed.append((topic, message))
        return []

    with McapRecorder(tmp_path / "r.mcap", KEYS, derive=derive) as recorder:  # type: ignore[arg-type]
        recorder.record(KEYS.telemetry("uav1"), msgspec.json.encode(_circle("uav1", 3)))
        recorder.record(KEYS.telemetry("uav1"), b'{"vehicle_id": 7}')  # JSON, not Telemetry
        recorder.record("skyquill/elsewhere/x", b"[1, 2]")  # no known type
        recorder.record(KEYS.telemetry("uav1"), b"{not json")
    assert recorder.messages == 3 and recorder.skipped == 1
    assert handed == [
        (KEYS.telemetry("uav1"), _circle("uav1", 3)),
        (KEYS.telemetry("uav1"), None),
        ("skyquill/elsewhere/x", None),
    ]

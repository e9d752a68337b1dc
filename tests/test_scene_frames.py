"""The scene's frames carry each vehicle's attitude and its writing point (issue 36): a tilted
vehicle's transform in a recording decodes to the quaternion it sent, the brush quadrotor's
writing point hangs its brush's length down the body's z axis, and telemetry of an older agent
(no attitude, no writing point) still decodes and is drawn as before."""

from __future__ import annotations

import math
from pathlib import Path

import msgspec
import numpy as np
import pytest
from mcap.reader import make_reader
from scene_decode import decoded
from scipy.spatial.transform import Rotation

from bus.keys import ShowKeys
from bus.messages import Telemetry
from bus.recorder import McapRecorder
from scene.encode import encoded
from scene.models import BRUSH_LENGTH_M, MARKER_M_BODY, SPONGE_TIP_M_BODY
from scene.show_scene import PATHS_TOPIC, TF_TOPIC, ShowScene
from scene.vehicles import transforms, writing_point_frame
from showfile import load_show
from vehicle_agent.backends.base import VehicleSnapshot
from vehicle_agent.backends.sim import SimVehicle
from vehicle_agent.motion import plan_move
from vehicle_agent.runner_io import telemetry_message
from vehicles.hexarotor_sponge.params import HexarotorParams
from vehicles.omni_wheel.geometry import OmniGeometry
from vehicles.quadrotor_brush.params import BrushParams

SHOW = load_show("shows/mixed.yaml")
KEYS = ShowKeys(SHOW.show_id)
T0_NS = 1_900_000_000 * 10**9
HOME = (0.0, -1.2, 0.0)


def _tilted_quadrotor() -> VehicleSnapshot:
    """The simulated brush quadrotor 1 m over the board (brush hanging free), at the tick of its
    largest tilt while it speeds up eastwards."""
    vehicle = SimVehicle(HOME)
    vehicle.takeoff((0.0, -1.2, 1.0))
    for _ in range(2_000):
        if vehicle.tick(None).mode == "hold":
            break
    move = plan_move((0.0, -1.2, 1.0), (1.5, -1.2, 1.0), vehicle.t_s, v_max_mps=1.5,
                     a_max_mps2=3.0)  # fmt: skip
    snaps = [vehicle.tick(move.setpoint(vehicle.t_s)) for _ in range(60)]
    return max(snaps, key=lambda s: _tilt_rad(s.attitude_xyzw_enu))


def _tilt_rad(q: tuple[float, float, float, float] | None) -> float:
    assert q is not None
    body_z = Rotation.from_quat(q).apply([0.0, 0.0, 1.0])
    return math.acos(min(1.0, body_z[2]))


def _record(path: Path, samples: list[bytes]) -> dict[str, list[object]]:
    """``samples`` (telemetry JSON of uav1, a second apart) recorded with the scene, every
    channel decoded."""
    scene = ShowScene(SHOW)
    with McapRecorder(path, KEYS, derive=scene.derive) as recorder:
        for i, payload in enumerate(samples):
            recorder.record(KEYS.telemetry("uav1"), payload, time_ns=T0_NS + i * 10**9)
    assert recorder.derive_failures == 0
    topics: dict[str, list[object]] = {}
    with path.open("rb") as f:
        for schema, channel, message in make_reader(f).iter_messages():
            assert schema is not None
            value = decoded(channel.message_encoding, schema.name, schema.data, message.data)
            topics.setdefault(channel.topic, []).append(value)
    return topics


def test_a_tilted_quadrotor_is_recorded_with_its_attitude_and_its_brush_tip(
    tmp_path: Path,
) -> None:
    snap = _tilted_quadrotor()
    assert math.degrees(_tilt_rad(snap.attitude_xyzw_enu)) > 5.0
    assert not snap.pen_contact  # 1 m over the board: the brush hangs at its full length
    sample = telemetry_message("uav1", "writing", snap, None, snap.t_s, job_id=None, progress=0.0)
    (tf,) = _record(tmp_path / "tilt.mcap", [msgspec.json.encode(sample)])[TF_TOPIC]
    body, tip = tf.transforms  # type: ignore[attr-defined]
    assert (body.parent_frame_id, body.child_frame_id) == ("world", "uav1")
    sent = snap.attitude_xyzw_enu
    assert (body.rotation.x, body.rotation.y, body.rotation.z, body.rotation.w) == sent
    assert (tip.parent_frame_id, tip.child_frame_id) == ("uav1", "uav1/writing_point")
    offset_m_body = (tip.translation.x, tip.translation.y, tip.translation.z)
    assert offset_m_body == pytest.approx((0.0, 0.0, -BrushParams().length_m), abs=1e-9)
    # the frames composed put the writing point where the simulated brush tip is
    p = np.array([body.translation.x, body.translation.y, body.translation.z])
    world_tip = p + Rotation.from_quat(sent).apply(offset_m_body)
    assert world_tip == pytest.approx(snap.pen_tip_m_enu, abs=1e-9)


def test_telemetry_of_an_older_agent_decodes_and_is_drawn_at_its_reference_point(
    tmp_path: Path,
) -> None:
    old = [
        b'{"vehicle_id":"uav1","t_s":%d,"state":"writing","position_m_enu":[%d,0.5,1.0],'
        b'"velocity_mps_enu":[0,0,0],"pen_down":true,"job_id":"j1"}' % (i, i)
        for i in range(3)
    ]
    sample = msgspec.json.decode(old[0], type=Telemetry)
    assert sample.attitude_xyzw_enu is None and sample.writing_point_m_enu is None
    topics = _record(tmp_path / "old.mcap", old)
    frames = [m.transforms for m in topics[TF_TOPIC]]  # type: ignore[attr-defined]
    assert all(len(f) == 1 for f in frames)  # no writing-point frame, no setpoint
    rotation = frames[-1][0].rotation
    assert (rotation.x, rotation.y, rotation.z, rotation.w) == (0.0, 0.0, 0.0, 1.0)
    paths = topics[PATHS_TOPIC][-1].entities[0]  # type: ignore[attr-defined]
    ink = next(line for line in paths.lines if line.type == 2)  # LINE_LIST
    ink = [(p.x, p.y, p.z) for p in ink.points]
    assert ink == [(0, 0.5, 1), (1, 0.5, 1), (1, 0.5, 1), (2, 0.5, 1)]


def test_ink_is_laid_where_the_writing_point_went_not_the_body() -> None:
    scene = ShowScene(SHOW)
    for i in range(3):
        sample = Telemetry(
            vehicle_id="uav1", t_s=i * 0.05, state="writing",
            position_m_enu=(i * 0.1, 0.0, 0.33), velocity_mps_enu=(0.0, 0.0, 0.0),
            reference_m_enu=(i * 0.1, 0.0, 0.33), pen_down=True, job_id="j1",
            writing_point_m_enu=(i * 0.1, 0.0, 0.0),
        )  # fmt: skip
        scene.telemetry(sample, T0_NS + i * 10**9)
    paths = scene._paths["uav1"]
    assert paths.ink == [(0.0, 0.0, 0.0), (0.1, 0.0, 0.0), (0.1, 0.0, 0.0), (0.2, 0.0, 0.0)]
    assert [p[2] for p in paths.flown] == [0.33] * 3  # the line held against the plan's


def test_an_unnormalised_attitude_is_drawn_as_the_rotation_it_means() -> None:
    q = Rotation.from_euler("xyz", [0.3, -0.2, 1.1]).as_quat()
    sample = Telemetry(
        vehicle_id="uav2", t_s=0.0, state="writing", position_m_enu=(1.0, 2.0, 3.0),
        velocity_mps_enu=(0.0, 0.0, 0.0), attitude_xyzw_enu=tuple(2.0 * q),
        writing_point_m_enu=(1.2, 2.0, 2.5),
    )  # fmt: skip
    message = encoded(TF_TOPIC, transforms(sample, T0_NS))
    tf = decoded("protobuf", message.schema_name, message.schema_data, message.payload)
    body, tip = tf.transforms
    got = [body.rotation.x, body.rotation.y, body.rotation.z, body.rotation.w]
    assert got == pytest.approx(q, abs=1e-12)
    assert tip.child_frame_id == writing_point_frame("uav2")
    offset = Rotation.from_quat(q).inv().apply([0.2, 0.0, -0.5])
    assert [tip.translation.x, tip.translation.y, tip.translation.z] == pytest.approx(offset)


def test_the_models_dimensions_are_the_rooms() -> None:
    assert BrushParams().length_m == BRUSH_LENGTH_M
    assert HexarotorParams().tip_m_body == pytest.approx((SPONGE_TIP_M_BODY, 0.0, 0.0))
    g = OmniGeometry()
    marker = (g.joint1_x_m + 0.5 * g.front_link_m, 0.0, -g.wheel_radius_m)
    assert marker == pytest.approx(MARKER_M_BODY)

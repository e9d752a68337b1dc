"""The live view never holds a Zenoh callback (issue 36): while its viewer stalls, samples go
into a bounded queue that drops the oldest and counts them, and once the viewer goes on, the
newest samples are the ones drawn."""

from __future__ import annotations

import asyncio
import json
import threading
import time
from pathlib import Path

import foxglove
import msgspec
import pytest
import websockets
from mcap.reader import make_reader
from scene_decode import decoded

from bus.keys import ShowKeys
from bus.messages import Telemetry
from scene.live import LiveView
from scene.show_scene import scene_channels
from showfile import load_show

SHOW = load_show("shows/mixed.yaml")
KEYS = ShowKeys(SHOW.show_id)
QUEUED = 100
SAMPLES = 5_000


def _sample(i: int) -> bytes:
    sample = Telemetry(vehicle_id="uav1", t_s=i * 0.05, state="writing",
                       position_m_enu=(i * 0.001, 0.0, 1.0),
                       velocity_mps_enu=(0.0, 0.0, 0.0))  # fmt: skip
    return msgspec.json.encode(sample)


def test_a_stalled_viewer_never_holds_the_callback_and_the_oldest_samples_go(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    context = foxglove.Context()
    sink = foxglove.open_mcap(tmp_path / "live.mcap", context=context)
    stalled, go_on = threading.Event(), threading.Event()
    payloads = [_sample(i) for i in range(SAMPLES)]
    key = KEYS.telemetry("uav1")
    with LiveView(SHOW, context, max_queued=QUEUED) as view:
        draw = view.scene.telemetry

        def slow_viewer(t: Telemetry, stamp_ns: int) -> object:
            stalled.set()
            go_on.wait(timeout=60.0)
            return draw(t, stamp_ns)

        monkeypatch.setattr(view.scene, "telemetry", slow_viewer)
        view.on_sample(key, payloads[0])
        assert stalled.wait(timeout=10.0)  # the view's thread is stuck in the viewer

        def zenoh() -> None:
            for payload in payloads[1:]:
                view.on_sample(key, payload)
            view.on_sample(KEYS.vehicle_status("uav1"), b"{}")  # not drawn: never queued

        callbacks = threading.Thread(target=zenoh)
        started_s = time.perf_counter()
        callbacks.start()
        callbacks.join(timeout=10.0)
        took_s = time.perf_counter() - started_s
        assert not callbacks.is_alive(), "a callback waited on the stalled viewer"
        assert took_s < 2.0, f"{SAMPLES} callbacks took {took_s:.2f} s"
        assert view.samples == SAMPLES
        assert view.dropped == SAMPLES - 1 - QUEUED
        go_on.set()
        deadline = time.monotonic() + 30.0
        while view.drawn < 1 + QUEUED and time.monotonic() < deadline:
            time.sleep(0.01)
        assert view.drawn == 1 + QUEUED
    sink.close()
    drawn_x = []
    with (tmp_path / "live.mcap").open("rb") as f:
        for schema, channel, message in make_reader(f).iter_messages(topics=["/tf"]):
            assert schema is not None
            tf = decoded(channel.message_encoding, schema.name, schema.data, message.data)
            drawn_x.append(round(tf.transforms[0].translation.x * 1000))
    assert drawn_x == [0, *range(SAMPLES - QUEUED, SAMPLES)]


def test_a_sample_that_cannot_be_drawn_is_counted_and_the_view_goes_on() -> None:
    with LiveView(SHOW, foxglove.Context()) as view:
        view.on_sample(KEYS.telemetry("uav1"), b'{"vehicle_id": 7}')
        view.on_sample(KEYS.telemetry("uav1"), _sample(1))
        deadline = time.monotonic() + 10.0
        while view.drawn < 1 and time.monotonic() < deadline:
            time.sleep(0.01)
        assert (view.failures, view.drawn, view.dropped) == (1, 1, 0)


def test_a_viewer_that_connects_before_any_sample_is_told_of_every_channel() -> None:
    """Every channel exists before the server starts: a viewer connecting to a show that has
    sent nothing yet is advertised all of the scene's topics at once, so none opens later
    while it is connected (foxglove-sdk can then refuse its subscription: scene.live)."""
    context = foxglove.Context()
    LiveView(SHOW, context)
    server = foxglove.start_server(name="advertise", host="127.0.0.1", port=0, context=context)

    async def first_advertise() -> set[str]:
        url = f"ws://127.0.0.1:{server.port}"
        async with websockets.connect(url, subprotocols=["foxglove.sdk.v1"]) as ws:  # type: ignore[arg-type]
            while True:
                op = json.loads(await asyncio.wait_for(ws.recv(), timeout=10.0))
                if op["op"] == "advertise":
                    return {channel["topic"] for channel in op["channels"]}

    try:
        topics = asyncio.run(first_advertise())
    finally:
        server.stop()
    assert topics == {channel.topic for channel in scene_channels()}
    assert {"/tf", "/scene/venue", "/scene/vehicles", "/scene/paths"} <= topics

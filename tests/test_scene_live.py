"""``skyquill view``: a secured show served live to Foxglove over its WebSocket protocol, watched
by a real WebSocket client that subscribes and decodes the scene with the schemas advertised;
stopping the view leaves the show running (issue 36)."""

from __future__ import annotations

import asyncio
import base64
import json
import os
import signal
import struct
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import websockets
from scene_decode import protobuf_class
from show_probe import all_alive, snapshot_when

from bus.session import free_tcp_endpoint
from cli.main import main as skyquill
from cli.showrun import ShowRun, derived_show
from showfile import load_show

pytestmark = [pytest.mark.multiprocess, pytest.mark.slow, pytest.mark.timeout(180)]

AIRSHOW = Path(__file__).resolve().parent.parent / "shows" / "airshow-2014.yaml"
SUBPROTOCOLS = ["foxglove.sdk.v1", "foxglove.websocket.v1"]
MESSAGE_DATA = 0x01
"""Opcode of a server's binary message carrying one subscribed channel's message."""
STATUS_ERROR = 2
"""Level of a server's status message that reports an error (e.g. a subscription refused)."""


@pytest.fixture(scope="module")
def show_run(tmp_path_factory: pytest.TempPathFactory) -> Iterator[ShowRun]:
    out = tmp_path_factory.mktemp("view")
    vehicles = load_show(AIRSHOW).vehicles[:2]
    path, show = derived_show(AIRSHOW, out, time_scale=4.0, vehicles=vehicles)
    assert show.security.mode == "mtls"
    assert skyquill(["keys", str(path), "--client", "view", "--role", "watcher"]) == 0
    with ShowRun(path, show, log_dir=out / "logs") as run:
        yield run


def _port() -> int:
    return int(free_tcp_endpoint().rsplit(":", 1)[1])


async def _watch(url: str, topics: set[str], timeout_s: float) -> dict[str, Any]:
    """Subscribe to ``topics`` once advertised; the first message of each, decoded. A status
    the server reports as an error (a subscription it refused) fails at once."""
    got: dict[str, Any] = {}
    async with websockets.connect(url, subprotocols=SUBPROTOCOLS) as ws:  # type: ignore[arg-type]
        channels: dict[int, dict[str, Any]] = {}
        subscribed: dict[int, dict[str, Any]] = {}
        deadline = time.monotonic() + timeout_s
        while len(got) < len(topics) and time.monotonic() < deadline:
            frame = await asyncio.wait_for(ws.recv(), timeout=deadline - time.monotonic())
            if isinstance(frame, str):
                op = json.loads(frame)
                assert not (op["op"] == "status" and op["level"] == STATUS_ERROR), op
                if op["op"] != "advertise":
                    continue
                wanted = []
                for channel in op["channels"]:
                    if channel["topic"] in topics and channel["id"] not in channels:
                        channels[channel["id"]] = channel
                        sub_id = len(subscribed) + 1
                        subscribed[sub_id] = channel
                        wanted.append({"id": sub_id, "channelId": channel["id"]})
                if wanted:
                    await ws.send(json.dumps({"op": "subscribe", "subscriptions": wanted}))
                continue
            assert frame[0] == MESSAGE_DATA
            sub_id, _log_time_ns = struct.unpack_from("<IQ", frame, 1)
            channel = subscribed[sub_id]
            if channel["topic"] in got:
                continue
            assert channel["encoding"] == "protobuf"
            schema = base64.b64decode(channel["schema"])
            message = protobuf_class(channel["schemaName"], schema)()
            message.ParseFromString(frame[13:])
            got[channel["topic"]] = message
    return got


QUIT_LIMIT_S = 30.0
"""A view not gone this long after its Ctrl-C hangs, wall [s]. It goes in 0.2 s alone and with
four busy loops beside it (2026-12-02); a fresh clone's CI once waited more than 10 s for it
(2026-12-01, cause unknown: no stacks were taken then)."""


def _stopped_view_stderr(view: subprocess.Popen[str]) -> str:
    """The view's stderr once it has stopped; a view that hangs is made to print the stacks of
    its threads (faulthandler, on SIGABRT), which the failure shows."""
    try:
        return view.communicate(timeout=QUIT_LIMIT_S)[1]
    except subprocess.TimeoutExpired:
        view.send_signal(signal.SIGABRT)
        stacks = view.communicate(timeout=10)[1]
        pytest.fail(f"the view still ran {QUIT_LIMIT_S:.0f} s after its Ctrl-C:\n{stacks}")


def _ctrl_c_as_in_a_terminal() -> None:
    """The view's Ctrl-C as a terminal's foreground command has it, at its default. A suite
    started in the background by a non-interactive shell (``bash -c '...' &``) ignores SIGINT,
    its xdist workers too, and a child inherits that; a worker's SIGINT is Python's own again
    only after an in-process test removed an asyncio signal handler (the agent's, the
    orchestrator's). A view started with SIGINT ignored sat out its Ctrl-C, its main thread
    still in its loop 30 s later: 2 of about 10 fresh-clone runs (2026-12-01), as the tests
    before it on its worker had it."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def test_a_viewer_subscribes_decodes_the_scene_and_quitting_the_view_leaves_the_show(
    show_run: ShowRun,
) -> None:
    port = _port()
    view = subprocess.Popen(
        [sys.executable, "-m", "cli.main", "view", str(show_run.show_path), "--port", str(port)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=os.environ | {"PYTHONUNBUFFERED": "1", "PYTHONFAULTHANDLER": "1"},
        preexec_fn=_ctrl_c_as_in_a_terminal,
    )
    try:
        line = view.stdout.readline()  # type: ignore[union-attr]
        assert f"ws://127.0.0.1:{port}" in line, line
        got = asyncio.run(_watch(f"ws://127.0.0.1:{port}", {"/tf", "/scene/venue"}, 60.0))
        assert {"/tf", "/scene/venue"} <= got.keys(), got.keys()
        boards = {e.id for e in got["/scene/venue"].entities}
        assert {f"venue/board/{b.id}" for b in show_run.show.boards} <= boards
        frame = got["/tf"].transforms[0]
        vehicle = show_run.show.vehicle(frame.child_frame_id)
        home = vehicle.home_m_enu
        assert abs(frame.translation.x - home[0]) < 0.5 and abs(frame.translation.y - home[1]) < 0.5
    finally:
        view.send_signal(signal.SIGINT)
        err = _stopped_view_stderr(view)
    assert view.returncode == 0 and "Traceback" not in err, err
    # Both vehicles stay in the show. An agent silent for lost_after_s (1.5 s) under the suite's
    # load is briefly lost (a fresh clone's CI saw one, 2026-12-01) and back at its next status;
    # one the view had stopped would not come back.
    with show_run.client() as operator:
        shown = snapshot_when(operator, show_run.keys, "both vehicles alive", all_alive,
                              timeout_s=10.0)  # fmt: skip
    assert len(shown.vehicles) == 2

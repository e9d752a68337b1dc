"""Two shows of real autopilots side by side (SITL; ``pytest -m sitl``).

``scripts/sitl/start.py`` runs on two copies of ``shows/sitl-<autopilot>.yaml`` at the same
moment, their vehicles on unusual ports: both must say ready, on four different instance
numbers, without holding the agent's link: each vehicle then answers a connection on its
``mavlink_url`` (a PX4 one held before start.py started, as when ``skyquill up`` runs first).
Skipped, saying so, when $SKYQUILL_ARDUCOPTER_SITL / $SKYQUILL_PX4_SITL is not set.
"""

from __future__ import annotations

import os
import re
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[1]
START_PY = ROOT / "scripts" / "sitl" / "start.py"
ENV_BINARY = {"ardupilot": "SKYQUILL_ARDUCOPTER_SITL", "px4": "SKYQUILL_PX4_SITL"}
READY_LIMIT_S = 90.0
"""Longest wait for both shows' "all ready" (measured: ArduCopter 10-11 s, PX4 2-3 s)."""


def with_ports(show_text: str, ports: list[int]) -> tuple[str, int]:
    """The show with its vehicles' ``mavlink_url`` ports replaced by ``ports`` in order, and how
    many were replaced."""
    found = iter(ports)
    return re.subn(
        r'(mavlink_url: "(?:tcp|udpin):127\.0\.0\.1:)\d+"',
        lambda m: f'{m.group(1)}{next(found)}"',
        show_text,
    )


def free_ports(protocol: str, count: int) -> list[int]:
    """``count`` ports the kernel gives out now (well away from the instances' own ports)."""
    kind = socket.SOCK_STREAM if protocol == "tcp" else socket.SOCK_DGRAM
    sockets = [socket.socket(socket.AF_INET, kind) for _ in range(count)]
    for sock in sockets:
        sock.bind(("127.0.0.1", 0))
    ports = [int(sock.getsockname()[1]) for sock in sockets]
    for sock in sockets:
        sock.close()
    return ports


def wait_all_ready(procs: list[subprocess.Popen[str]], logs: list[Path]) -> None:
    deadline = time.monotonic() + READY_LIMIT_S
    while not all("all ready" in log.read_text() for log in logs):
        for proc, log in zip(procs, logs, strict=True):
            if proc.poll() is not None:
                pytest.fail(f"start.py exited {proc.returncode}:\n{log.read_text()}")
        if time.monotonic() > deadline:
            pytest.fail("not ready:\n" + "\n".join(log.read_text() for log in logs))
        time.sleep(0.5)


def heartbeat_from(conn: Any, system_id: int, timeout_s: float = 10.0) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        msg = conn.recv_match(type="HEARTBEAT", blocking=True, timeout=1.0)
        if msg is not None and msg.get_srcSystem() == system_id:
            return True
    return False


@pytest.mark.sitl
@pytest.mark.timeout(180)
@pytest.mark.parametrize("kind", ["ardupilot", "px4"])
def test_two_shows_run_side_by_side_and_leave_the_agent_link_free(
    kind: str, tmp_path: Path
) -> None:
    if not os.environ.get(ENV_BINARY[kind]):
        pytest.skip(f'{ENV_BINARY[kind]} not set: path of the {kind} SITL binary (README, "Real '
                    'autopilot SITL")')  # fmt: skip
    from pymavlink import mavutil

    protocol, scheme = ("tcp", "tcp") if kind == "ardupilot" else ("udp", "udpin")
    ports = free_ports(protocol, 4)
    show = (ROOT / "shows" / f"sitl-{kind}.yaml").read_text()
    early = None
    if kind == "px4":  # the agent of show a is up first and listens on its first port
        early = mavutil.mavlink_connection(f"udpin:127.0.0.1:{ports[0]}", source_system=254)
    procs, logs = [], []
    try:
        for name, pair in (("a", ports[:2]), ("b", ports[2:])):
            text, count = with_ports(show, pair)
            assert count == 2
            (tmp_path / f"{name}.yaml").write_text(text)
            logs.append(tmp_path / f"{name}.log")
            with open(logs[-1], "w") as log:
                procs.append(subprocess.Popen(
                    [sys.executable, str(START_PY), str(tmp_path / f"{name}.yaml"),
                     "--run-dir", str(tmp_path / f"run-{name}")],
                    cwd=ROOT, stdout=log, stderr=subprocess.STDOUT, text=True,
                ))  # fmt: skip
        wait_all_ready(procs, logs)
        outputs = "".join(log.read_text() for log in logs)
        numbers = re.findall(rf"{kind} instance (\d+), system id", outputs)
        assert len(set(numbers)) == 4, outputs
        said = re.findall(r"system id (\d+), agent link \w+:127\.0\.0\.1:(\d+),", outputs)
        system_ids = {int(port): int(system_id) for system_id, port in said}
        assert sorted(system_ids) == sorted(ports), outputs
        for k, port in enumerate(ports):
            system_id = system_ids[port]
            if early is not None and k == 0:
                assert heartbeat_from(early, system_id), f"{scheme}:{port}"
                continue
            conn = mavutil.mavlink_connection(f"{scheme}:127.0.0.1:{port}", source_system=254,
                                              autoreconnect=False)  # fmt: skip
            try:
                assert heartbeat_from(conn, system_id), f"{scheme}:{port}: {outputs}"
            finally:
                conn.close()
    finally:
        for proc in procs:
            proc.send_signal(signal.SIGINT)
        codes = [proc.wait(timeout=30) for proc in procs]
        if early is not None:
            early.close()
    assert codes == [0, 0]
    assert all("stopped 2 instance(s)" in log.read_text() for log in logs)

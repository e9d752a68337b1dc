"""``skyquill sim-mavlink SHOW.yaml`` as a process: it prints endpoints that the backend flies."""

from __future__ import annotations

import asyncio
import re
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from vehicle_agent.backends.mavlink.backend import MavlinkBackend
from vehicle_agent.backends.mavlink.errors import ArmingRefusedError
from vehicle_agent.backends.mavlink.settings import MavlinkSettings

pytestmark = pytest.mark.timeout(60)

SHOW = """
show_id: sim-mavlink-cli
time_scale: 2.0
boards:
  - {{id: b1, center_m_enu: [0.0, 0.0, 0.75], size_m: [1.4, 1.4], writing_area_m: [1.2, 1.2]}}
vehicles:
  - {{id: ground, backend: sim, board: b1, home_m_enu: [-2.0, -1.2, 0.0]}}
  - {{id: uav2, backend: mavlink, mavlink_url: "udp:127.0.0.1:{p1}", board: b1,
     home_m_enu: [0.0, -1.2, 0.0]}}
  - {{id: uav3, backend: mavlink, mavlink_url: "udp:127.0.0.1:{p2}", mavlink_system_id: 9,
     board: b1, home_m_enu: [1.0, -1.2, 0.0]}}
"""
ENDPOINT = re.compile(r"^(\S+) (udp:127\.0\.0\.1:\d+) system_id=(\d+)$")


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def skyquill(*args: str) -> list[str]:
    return [sys.executable, "-m", "cli.main", *args]


@pytest.fixture
def sim_mavlink(tmp_path: Path) -> Iterator[dict[str, tuple[str, int]]]:
    show = tmp_path / "show.yaml"
    show.write_text(SHOW.format(p1=free_udp_port(), p2=free_udp_port()), encoding="utf-8")
    argv = skyquill("sim-mavlink", str(show), "--position-source-delay", "0.5",
                    "--refuse-arm", "uav3=Compass not calibrated")  # fmt: skip
    process = subprocess.Popen(argv, stdout=subprocess.PIPE, text=True)
    try:
        assert process.stdout is not None
        endpoints = {}
        for _ in range(2):
            line = process.stdout.readline().strip()
            match = ENDPOINT.match(line)
            assert match, line
            endpoints[match[1]] = (match[2], int(match[3]))
        yield endpoints
        process.send_signal(signal.SIGINT)
        assert process.wait(timeout=10) == 0
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()


def test_sim_mavlink_prints_endpoints_that_fly(sim_mavlink: dict[str, tuple[str, int]]) -> None:
    assert {name: sysid for name, (_, sysid) in sim_mavlink.items()} == {"uav2": 2, "uav3": 9}

    async def fly(url: str) -> None:
        backend = MavlinkBackend(MavlinkSettings(url=url, origin_m_enu=(0.0, -1.2, 0.0)))
        await backend.start()
        assert backend.state.system_id == 2
        await asyncio.sleep(0.5)  # the position source (0.5 s of vehicle time)
        await backend.takeoff((0.0, -1.2, 0.5))
        k, t0 = 0, time.monotonic()
        snapshot = await backend.tick(None, 0.0)
        while snapshot.mode != "hold":
            k += 1
            await asyncio.sleep(max(0.0, t0 + k * 0.01 / 2.0 - time.monotonic()))
            snapshot = await backend.tick(None, k * 0.01)
            assert k < 800, snapshot
        assert snapshot.position_m_enu[2] > 0.4 and snapshot.fault is None
        await backend.estop()
        await backend.close()

    async def refused(url: str) -> None:
        backend = MavlinkBackend(MavlinkSettings(url=url, origin_m_enu=(1.0, -1.2, 0.0)))
        await backend.start()
        with pytest.raises(ArmingRefusedError, match="PreArm: Compass not calibrated"):
            await backend.takeoff((1.0, -1.2, 0.5))
        await backend.close()

    asyncio.run(fly(sim_mavlink["uav2"][0]))
    asyncio.run(refused(sim_mavlink["uav3"][0]))


def test_sim_mavlink_without_mavlink_vehicles_says_so(tmp_path: Path) -> None:
    show = tmp_path / "show.yaml"
    text = SHOW.format(p1=1, p2=2).replace("backend: mavlink", "backend: sim")
    show.write_text(text, encoding="utf-8")
    result = subprocess.run(skyquill("sim-mavlink", str(show)), capture_output=True, text=True,
                            timeout=30, check=False)  # fmt: skip
    assert result.returncode == 2
    assert "no vehicle with backend: mavlink" in result.stderr

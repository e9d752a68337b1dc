"""The links of the multi-host test: Linux network namespaces joined by impaired links.

Three namespaces (``ground``, ``rack1``, ``rack2``), each with its own loopback; each companion
joined to the ground station by a TUN device at each end and this file run as ``wire`` between
them: every IP packet is 50 ms late each way and 5 % are dropped at random, as ``tc netem delay
50ms loss 5%`` would (this machine's kernel has no ``sch_netem``; TCP sees real loss either way);
``cut`` drops everything. Addresses: 10.77.1.1 (ground) - 10.77.1.2 (rack1), 10.77.2.1 (ground) -
10.77.2.2 (rack2). Needs root (``ip netns``), iproute2 and ``/dev/net/tun``; the fixture skips
with the reason otherwise, and removes the namespaces, their processes and links at the end, also
on failure. The test here checks the links themselves.
"""

from __future__ import annotations

import contextlib
import ctypes
import fcntl
import heapq
import os
import random
import select
import shutil
import signal
import statistics
import struct
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest

DELAY_S = 0.050
"""Every packet on a link between hosts is this late, each way, [s]."""
LOSS = 0.05
"""Share of the packets dropped on a link between hosts, each way."""


def _why_no_namespaces() -> str | None:
    if not sys.platform.startswith("linux"):
        return "network namespaces are Linux only"
    if os.geteuid() != 0:
        return "creating network namespaces (ip netns) and TUN links needs root"
    if shutil.which("ip") is None:
        return "iproute2 (ip) is not installed"
    if not Path("/dev/net/tun").exists():
        return "no /dev/net/tun for the links between namespaces"
    return None


def _ip(*args: str) -> None:
    done = subprocess.run(["ip", *args], capture_output=True, text=True, timeout=10)
    if done.returncode != 0:
        raise RuntimeError(f"ip {' '.join(args)}: {done.stderr.strip()}")


@dataclass
class Venue:
    """Three namespaces and two impaired links; ``netns``: host -> namespace, ``wires``: the
    companion host -> the process carrying its link."""

    tag: str
    netns: dict[str, str] = field(default_factory=dict)
    wires: dict[str, subprocess.Popen[str]] = field(default_factory=dict)

    def build(self) -> None:
        for host in ("ground", "rack1", "rack2"):
            name = f"{self.tag}{host[0]}{host[-1]}"
            _ip("netns", "add", name)
            self.netns[host] = name
            _ip("-n", name, "link", "set", "lo", "up")
        ground = self.netns["ground"]
        for subnet, host in ((1, "rack1"), (2, "rack2")):
            near, far, other = f"{self.tag}g{subnet}", f"{self.tag}h{subnet}", self.netns[host]
            ends = (
                (ground, near, f"10.77.{subnet}.1", f"10.77.{subnet}.2"),
                (other, far, f"10.77.{subnet}.2", f"10.77.{subnet}.1"),
            )
            for netns, dev, local, peer in ends:
                _ip("-n", netns, "tuntap", "add", "dev", dev, "mode", "tun")
                _ip("-n", netns, "addr", "add", local, "peer", peer, "dev", dev)
                _ip("-n", netns, "link", "set", dev, "up")
            self.wires[host] = subprocess.Popen(
                [sys.executable, __file__, "wire", ground, near, other, far],
                stdin=subprocess.PIPE,
                text=True,
            )

    def partition(self, host: str, cut: bool) -> None:
        """Drop every packet on ``host``'s link (``cut``), or go back to delay and loss."""
        stdin = self.wires[host].stdin
        assert stdin is not None
        stdin.write("cut\n" if cut else "heal\n")
        stdin.flush()

    def exec_argv(self, host: str, *argv: str) -> list[str]:
        return ["ip", "netns", "exec", self.netns[host], *argv]

    def tear_down(self) -> None:
        """Kill what still runs in our namespaces (by pid), stop the wires, delete the
        namespaces (their links go with them)."""
        for netns in self.netns.values():
            pids = subprocess.run(
                ["ip", "netns", "pids", netns], capture_output=True, text=True, timeout=10
            ).stdout.split()
            for pid in pids:
                with contextlib.suppress(ProcessLookupError):
                    os.kill(int(pid), signal.SIGKILL)
        for wire in self.wires.values():
            wire.kill()
            wire.wait()
        for netns in self.netns.values():
            subprocess.run(["ip", "netns", "del", netns], capture_output=True, timeout=10)


@pytest.fixture(name="venue")
def venue_fixture() -> Iterator[Venue]:
    reason = _why_no_namespaces()
    if reason is not None:
        pytest.skip(reason)
    built = Venue(tag=f"sq{os.getpid() % 100000}")
    try:
        try:
            built.build()
        except RuntimeError as exc:
            pytest.skip(f"network namespaces unavailable here: {exc}")
        yield built
    finally:
        built.tear_down()


# --- the link between two namespaces: a userspace wire (this kernel may lack sch_netem) --------

CLONE_NEWNET = 0x40000000
TUNSETIFF = 0x400454CA
IFF_TUN_NO_PI = 0x0001 | 0x1000


def _open_tun(netns: str, dev: str) -> int:
    """Enter ``netns`` (this whole process) and attach to its TUN device ``dev``."""
    libc = ctypes.CDLL("libc.so.6", use_errno=True)
    ns_fd = os.open(f"/var/run/netns/{netns}", os.O_RDONLY)
    try:
        if libc.setns(ns_fd, CLONE_NEWNET) != 0:
            raise OSError(ctypes.get_errno(), f"setns {netns}")
    finally:
        os.close(ns_fd)
    fd = os.open("/dev/net/tun", os.O_RDWR | os.O_NONBLOCK)
    fcntl.ioctl(fd, TUNSETIFF, struct.pack("16sH", dev.encode(), IFF_TUN_NO_PI))
    return fd


def wire(ns_a: str, dev_a: str, ns_b: str, dev_b: str) -> None:
    """Carry IP packets between two TUN devices: each one DELAY_S late, LOSS of them dropped,
    all dropped while cut (``cut``/``heal`` lines on stdin; end of stdin ends it)."""
    ends = [_open_tun(ns_a, dev_a), _open_tun(ns_b, dev_b)]
    other = {ends[0]: ends[1], ends[1]: ends[0]}
    rng = random.Random(15)
    queue: list[tuple[float, int, int, bytes]] = []
    cut, count, control = False, 0, sys.stdin.fileno()
    while True:
        wait_s = max(0.0, queue[0][0] - time.monotonic()) if queue else 1.0
        ready, _, _ = select.select([*ends, control], [], [], wait_s)
        for fd in ready:
            if fd == control:
                said = os.read(control, 256).split()
                if not said:
                    return
                cut = said[-1] == b"cut"
                continue
            with contextlib.suppress(BlockingIOError):
                while packet := os.read(fd, 65536):
                    if not cut and rng.random() >= LOSS:
                        count += 1
                        heapq.heappush(
                            queue, (time.monotonic() + DELAY_S, count, other[fd], packet)
                        )
        while queue and queue[0][0] <= time.monotonic():
            _, _, out, packet = heapq.heappop(queue)
            with contextlib.suppress(OSError):
                os.write(out, packet)


ECHO = (
    "import socket\n"
    "s = socket.socket(); s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)\n"
    "s.bind(('10.77.1.1', 9000)); s.listen(); c, _ = s.accept()\n"
    "while data := c.recv(65536):\n    c.sendall(data)\n"
)
ROUND_TRIPS = (
    "import socket, sys, time\n"
    "s = socket.create_connection(('10.77.1.1', 9000), timeout=float(sys.argv[1]))\n"
    "for _ in range(40):\n"
    "    t = time.monotonic(); s.sendall(b'x' * 100); s.recv(100)\n"
    "    print(time.monotonic() - t)\n"
)


@pytest.mark.multiprocess
def test_a_link_delays_each_way_loses_packets_and_can_be_cut(venue: Venue) -> None:
    server = subprocess.Popen(venue.exec_argv("ground", sys.executable, "-c", ECHO))
    try:
        time.sleep(1.0)
        argv = venue.exec_argv("rack1", sys.executable, "-c", ROUND_TRIPS, "10")
        out = subprocess.run(argv, capture_output=True, text=True, timeout=60, check=True)
        round_trips_s = [float(line) for line in out.stdout.split()]
        assert 2 * DELAY_S <= statistics.median(round_trips_s) < 2 * DELAY_S + 0.05
        venue.partition("rack1", cut=True)
        argv = venue.exec_argv("rack2", sys.executable, "-c", ROUND_TRIPS, "1")
        assert subprocess.run(argv, capture_output=True, timeout=30).returncode != 0  # no route
        argv = venue.exec_argv("rack1", sys.executable, "-c", ROUND_TRIPS, "1")
        assert subprocess.run(argv, capture_output=True, timeout=30).returncode != 0  # cut
    finally:
        server.kill()
        server.wait()


if __name__ == "__main__" and sys.argv[1:2] == ["wire"]:
    wire(*sys.argv[2:6])

"""A TCP relay in front of the show's router that can cut one process off (``bench_chaos.py``).

Every client of the show connects to the router through it (the show's ``zenoh.connect`` is the
relay's port; the router listens on its own). :meth:`CutRelay.cutting` cuts one process off for a
while: its links stop carrying bytes both ways, and links it opens meanwhile are held unanswered,
as a Wi-Fi drop or a pulled cable would do; nothing is reset and nothing is lost (bytes in flight
wait, as TCP's retransmissions would), so each side learns of it only from its link lease. The
relay tells whose a link is by the process that owns the connecting socket (``/proc``).

This machine's kernel has no ``sch_netem`` and no packet filter, so the cut is made here, in user
space, as ``tests/test_multihost_venue.py`` makes its impaired links.
"""

from __future__ import annotations

import contextlib
import os
import socket
import threading
from collections.abc import Callable, Iterator
from pathlib import Path


def _socket_inodes(pid: int) -> set[str]:
    """The inodes of the sockets ``pid`` holds open."""
    found = set()
    with contextlib.suppress(OSError):
        for fd in Path(f"/proc/{pid}/fd").iterdir():
            with contextlib.suppress(OSError):
                target = os.readlink(fd)
                if target.startswith("socket:["):
                    found.add(target[8:-1])
    return found


def _inode_of_local_port(port: int) -> str | None:
    """The inode of the TCP socket bound to local ``port`` on loopback (IPv4)."""
    with contextlib.suppress(OSError):
        for line in Path("/proc/net/tcp").read_text().splitlines()[1:]:
            fields = line.split()
            if int(fields[1].rsplit(":", 1)[1], 16) == port:
                return fields[9]
    return None


class CutRelay:
    """Relays ``listen_port`` to ``router_port`` on 127.0.0.1; ``owners()`` names the processes
    that may be cut off (name -> pid; set once they run)."""

    def __init__(self, listen_port: int, router_port: int) -> None:
        self.router_port = router_port
        self.owners: Callable[[], dict[str, int]] = dict
        self._server = socket.create_server(("127.0.0.1", listen_port))
        self._cut: set[str] = set()
        self._open = threading.Condition()
        self._closed = False
        threading.Thread(target=self._accept, daemon=True, name="relay").start()

    def close(self) -> None:
        with self._open:
            self._closed = True
            self._cut.clear()
            self._open.notify_all()
        self._server.close()

    @contextlib.contextmanager
    def cutting(self, name: str) -> Iterator[None]:
        """``name``'s links carry nothing for the life of the context."""
        with self._open:
            self._cut.add(name)
        try:
            yield
        finally:
            with self._open:
                self._cut.discard(name)
                self._open.notify_all()

    def _owner(self, peer_port: int) -> str | None:
        inode = _inode_of_local_port(peer_port)
        if inode is None:
            return None
        for name, pid in self.owners().items():
            if inode in _socket_inodes(pid):
                return name
        return None

    def _wait_uncut(self, owner: str | None) -> bool:
        """Block while ``owner`` is cut off; False once the relay is closed."""
        with self._open:
            while owner in self._cut and not self._closed:
                self._open.wait()
            return not self._closed

    def _accept(self) -> None:
        while True:
            try:
                client, (_, port) = self._server.accept()
            except OSError:
                return
            owner = self._owner(port)
            threading.Thread(target=self._link, args=(client, owner), daemon=True).start()

    def _link(self, client: socket.socket, owner: str | None) -> None:
        if not self._wait_uncut(owner):  # a link opened while cut off waits unanswered
            client.close()
            return
        try:
            router = socket.create_connection(("127.0.0.1", self.router_port))
        except OSError:
            client.close()
            return
        for a, b in ((client, router), (router, client)):
            threading.Thread(target=self._pump, args=(a, b, owner), daemon=True).start()

    def _pump(self, source: socket.socket, sink: socket.socket, owner: str | None) -> None:
        try:
            while self._wait_uncut(owner):
                data = source.recv(65536)
                if not data or not self._wait_uncut(owner):
                    break
                sink.sendall(data)
        except OSError:
            pass
        for end in (source, sink):
            with contextlib.suppress(OSError):
                end.shutdown(socket.SHUT_RDWR)

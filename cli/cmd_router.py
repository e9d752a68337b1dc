"""``skyquill router SHOW.yaml``: the show's Zenoh router, a process of its own.

Its Zenoh configuration is the one every process of the show builds
(``bus.session.build_config`` with role ``router``, from the show's settings for the identity
``router``): the show's listen endpoints, mutual TLS and the generated access control when the
show is secured, and the same link lease and reconnection settings as the clients. In a show
across several machines, ``--host NAME`` runs that host's router (``zenoh.hosts``; a companion
host's router links to the ground station's, see ``trust/hosts.py``). ``skyquill up``
starts it first, restarts it within a second when it dies (every client reconnects by itself and
declares its subscribers, queryables and liveliness tokens again) and stops it last.

A secured router watches the show's list of outside clients (``trust/clients.py``): when
``skyquill keys --client`` or ``--revoke`` changes it, the router closes its session and opens
it again at once with its trusted issuers and access control made anew (Zenoh reads both only
when a session opens), so a revoked client can no longer connect within a second
(``CLIENTS_POLL_S`` plus the reopening, about 0.1 s) while every other client reconnects by
itself, as after a restart.
"""

from __future__ import annotations

import argparse
import sys
import threading
import time
from pathlib import Path

NAME = "router"
CLIENTS_POLL_S = 0.25
"""How often the router looks whether the show's list of outside clients changed, [s]."""
HELP = "Run a show's Zenoh router (skyquill up supervises it; clients reconnect when it restarts)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("show", type=Path, help="show file (YAML)")
    parser.add_argument("--host", default=None, help="the host whose router this is (zenoh.hosts)")


def run(args: argparse.Namespace) -> int:
    from bus.session import SessionOpenError, open_session
    from cli.supervisor import install_stop_signals
    from showfile import ShowError, load_show
    from trust.clients import registry_path
    from trust.hosts import HostError, host_named, router_identity
    from trust.settings import session_settings

    stop = threading.Event()
    install_stop_signals(stop.set)
    try:
        show = load_show(args.show)
        identity = "router"
        if args.host is not None:
            identity = router_identity(args.host, host_named(show, args.host))
        elif show.zenoh.hosts:
            raise HostError(
                f"{args.show}: the show spans hosts ({', '.join(show.zenoh.hosts)}): "
                "give --host NAME"
            )
        clients = registry_path(show.keys_dir) if show.security.mode != "none" else None
        seen = _stamp(clients)  # before the settings read the list: no change goes unseen
        settings = session_settings(show, identity)
    except (ShowError, SessionOpenError, HostError) as exc:
        print(f"skyquill router: {exc}", file=sys.stderr)
        return 2
    renewing_since_s: float | None = None
    while True:
        try:
            session = open_session(settings, role="router")
        except SessionOpenError as exc:
            print(f"skyquill router: {exc}", file=sys.stderr)
            return 1
        with session:
            if renewing_since_s is None:
                listen = ", ".join(settings.router_listen)
                linked = settings.router_connect
                print(
                    f"skyquill router: show {show.show_id} as {identity} on {listen}"
                    + (f", linked to {', '.join(linked)}" if linked else ""),
                    file=sys.stderr,
                    flush=True,
                )
            else:
                renewed_s = time.monotonic() - renewing_since_s
                print(
                    f"skyquill router: outside clients changed: trust and access control "
                    f"renewed in {renewed_s:.2f} s",
                    file=sys.stderr,
                    flush=True,
                )
            while not stop.wait(CLIENTS_POLL_S) and _stamp(clients) == seen:
                pass
            if stop.is_set():
                return 0
            renewing_since_s = time.monotonic()
            seen = _stamp(clients)
            try:  # made before the session closes: clients wait for the reopening alone
                settings = session_settings(show, identity)
            except SessionOpenError as exc:  # an unreadable list of clients: admit no one
                print(f"skyquill router: {exc}", file=sys.stderr)
                return 1


def _stamp(path: Path | None) -> tuple[int, int] | None:
    """What tells a changed file: modification time [ns] and size (None: no file)."""
    try:
        stat = path.stat() if path is not None else None
    except FileNotFoundError:
        return None
    return None if stat is None else (stat.st_mtime_ns, stat.st_size)

"""``skyquill router SHOW.yaml``: the show's Zenoh router, a process of its own.

Its Zenoh configuration is the one every process of the show builds
(``bus.session.build_config`` with role ``router``, from the show's settings for the identity
``router``): the show's listen endpoints, mutual TLS and the generated access control when the
show is secured, and the same link lease and reconnection settings as the clients. In a show
across several machines, ``--host NAME`` runs that host's router (``zenoh.hosts``; a companion
host's router links to the ground station's, see ``trust/hosts.py``). ``skyquill up``
starts it first, restarts it within a second when it dies (every client reconnects by itself and
declares its subscribers, queryables and liveliness tokens again) and stops it last.
"""

from __future__ import annotations

import argparse
import sys
import threading
from pathlib import Path

NAME = "router"
HELP = "Run a show's Zenoh router (skyquill up supervises it; clients reconnect when it restarts)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("show", type=Path, help="show file (YAML)")
    parser.add_argument("--host", default=None, help="the host whose router this is (zenoh.hosts)")


def run(args: argparse.Namespace) -> int:
    from bus.session import SessionOpenError, open_session
    from cli.supervisor import install_stop_signals
    from showfile import ShowError, load_show
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
        settings = session_settings(show, identity)
    except (ShowError, SessionOpenError, HostError) as exc:
        print(f"skyquill router: {exc}", file=sys.stderr)
        return 2
    try:
        session = open_session(settings, role="router")
    except SessionOpenError as exc:
        print(f"skyquill router: {exc}", file=sys.stderr)
        return 1
    with session:
        listen = ", ".join(settings.router_listen)
        linked = (
            f", linked to {', '.join(settings.router_connect)}" if settings.router_connect else ""
        )
        print(
            f"skyquill router: show {show.show_id} as {identity} on {listen}{linked}",
            file=sys.stderr,
            flush=True,
        )
        while not stop.wait(0.5):
            pass
    return 0

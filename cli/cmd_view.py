"""``skyquill view SHOW.yaml``: the running show, live, in Foxglove (read only).

The view is a watcher: it holds a watcher's certificate (``--client`` folder from ``skyquill
keys SHOW --client NAME --role watcher``; on the show's own machine, without ``--client``, the
watcher ``view`` is issued once and reused) and may only watch. It serves the scene
(``scene.live``) on Foxglove's WebSocket protocol: in Foxglove, Open connection -> Foxglove
WebSocket -> the printed URL, then import ``docs/foxglove-layout.json``. Stopping the view never
touches the show.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from bus.session import BusSettings
    from showfile import Show

NAME = "view"
HELP = "Serve the running show live to Foxglove (3D scene, plots, log); read only."
ROUTER_RELOAD_S = 2.0
"""Wait after issuing the watcher, in [s]: a running router re-reads its clients within a second
(``trust/clients.py``)."""
VIEW_CLIENT = "view"
"""The watcher issued for ``skyquill view`` on the show's machine."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("show", type=Path, help="show file (YAML)")
    parser.add_argument(
        "--client", type=Path, metavar="DIR", help="a watcher's folder from skyquill keys --client"
    )
    parser.add_argument("--host", default="127.0.0.1", help="address to serve on (127.0.0.1)")
    parser.add_argument("--port", type=int, default=8765, help="port (8765, Foxglove's; 0: any)")


def run(args: argparse.Namespace) -> int:
    from showfile import ShowError, load_show

    if not 0 <= args.port <= 65535:
        print(f"skyquill view: --port {args.port} is not a port (0-65535)", file=sys.stderr)
        return 2
    try:
        show = load_show(args.show)
    except ShowError as exc:
        print(f"skyquill view: {exc}", file=sys.stderr)
        return 2
    try:
        return _serve(show, args)
    except KeyboardInterrupt:
        print("skyquill view: stopped (the show goes on)", file=sys.stderr)
        return 0


def _settings(show: Show, client: Path | None) -> BusSettings:
    """A watcher's bus settings: the folder given, or the show machine's own ``view`` watcher."""
    from trust.pki import client_files
    from trust.settings import client_session_settings, session_settings

    if show.security.mode == "none":
        settings: BusSettings = session_settings(show, "operator")
        return settings
    if client is None:
        from cli.cmd_keys import issue_client_folder

        files = client_files(show.keys_dir, VIEW_CLIENT, "watcher")
        client = files.cert.parent
        if not files.cert.exists():
            client = issue_client_folder(show, VIEW_CLIENT, "watcher")
            time.sleep(ROUTER_RELOAD_S)  # a running router admits the new watcher meanwhile
    return client_session_settings(show, client)


def _serve(show: Show, args: argparse.Namespace) -> int:
    import foxglove

    from bus.keys import ShowKeys
    from bus.pubsub import subscribe_raw
    from bus.session import SessionOpenError, open_session
    from scene.live import LIVE_VENUE_PERIOD_S, LiveView
    from trust.pki import KeysError

    try:
        settings = _settings(show, args.client)
        session = open_session(settings, role="client", open_timeout_s=10.0)
    except (KeysError, SessionOpenError) as exc:
        print(f"skyquill view: {exc}", file=sys.stderr)
        return 1
    context = foxglove.Context()
    view = LiveView(show, context)  # opens every channel: before the server starts (scene.live)
    server = foxglove.start_server(
        name=f"skyquill {show.show_id}",
        host=args.host,
        port=args.port,
        context=context,
    )
    prefix = ShowKeys(show.show_id).prefix
    with session:
        subscribe_raw(session, f"{prefix}/**", lambda x: view.on_sample(x.key, x.payload))
        url = f"ws://{args.host}:{server.port}"
        print(
            f"skyquill view: show {show.show_id} live on {url}"
            " (Foxglove: Open connection -> Foxglove WebSocket; layout docs/foxglove-layout.json);"
            " Ctrl-C stops the view, never the show",
            flush=True,
        )
        try:
            while True:
                view.send_fixed()
                time.sleep(LIVE_VENUE_PERIOD_S)
        finally:
            view.close()
            server.stop()  # the session's close undeclares the subscriber

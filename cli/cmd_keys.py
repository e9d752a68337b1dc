"""``skyquill keys SHOW.yaml``: the show's CA and one certificate per process; ``--client NAME
--role R`` issues a certificate for an outside client and writes a Zenoh config that uses it;
``--revoke NAME`` shuts an issued client out: within a second the show's router no longer
accepts its certificate at connection nor admits it in its access control; no other certificate
changes and no vehicle restarts (``trust/clients.py``)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from showfile import Show

NAME = "keys"
HELP = "Create the show's certificates, issue one to an outside client, or revoke a client."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("show", type=Path, help="show file (YAML)")
    which = parser.add_mutually_exclusive_group()
    which.add_argument("--client", metavar="NAME", help="issue a certificate to an outside client")
    which.add_argument(
        "--revoke", metavar="NAME", help="shut an issued client out (its name is not reissued)"
    )
    parser.add_argument(
        "--role",
        choices=("watcher", "operator", "submitter"),
        default="watcher",
        help="what the client may do (default: watcher, read only)",
    )


def _client_config(endpoints: list[str], folder: Path) -> dict[str, object]:
    return {
        "mode": "client",
        "connect": {"endpoints": endpoints},
        "scouting": {"multicast": {"enabled": False}},
        "transport": {
            "link": {
                "tls": {
                    "root_ca_certificate": str(folder / "ca.pem"),
                    "connect_private_key": str(folder / "key.pem"),
                    "connect_certificate": str(folder / "cert.pem"),
                    "enable_mtls": True,
                    "verify_name_on_connect": True,
                }
            }
        },
    }


def issue_client_folder(show: Show, name: str, role: str) -> Path:
    """Issue ``name``'s certificate, admit it, write its Zenoh config; returns its folder."""
    from trust.clients import record_client
    from trust.hosts import endpoints
    from trust.pki import issue_client
    from trust.settings import as_tls

    files = issue_client(show.keys_dir, name, role, show_id=show.show_id)
    record_client(show.keys_dir, name, role)  # last: the router reloads with the issuer there
    folder = files.cert.parent
    connect = list(as_tls(endpoints(show, files.common_name).connect))
    config_path = folder / "zenoh-client.json5"
    config_path.write_text(json.dumps(_client_config(connect, folder), indent=2) + "\n")
    return folder


def run(args: argparse.Namespace) -> int:
    from showfile import ShowError, load_show
    from showfile.security import RESERVED_IDS
    from trust.clients import revoke_client
    from trust.pki import KeysError
    from trust.settings import ensure_show_keys

    try:
        show = load_show(args.show)
    except ShowError as exc:
        print(f"skyquill keys: {exc}", file=sys.stderr)
        return 2
    if show.security.mode == "none":
        print(f"skyquill keys: {args.show}: security is none: this show uses no keys")
        return 0
    name = args.client or args.revoke
    if name is not None and (
        not str(name).replace("-", "").replace("_", "").isalnum() or name in RESERVED_IDS
    ):
        option = "--client" if args.client else "--revoke"
        print(f"skyquill keys: {option} {name!r}: use letters, digits, - and _", file=sys.stderr)
        return 2
    try:
        made = ensure_show_keys(show)
        if args.revoke is not None:
            role = revoke_client(show.keys_dir, name)
            print(
                f"revoked client {name} ({role}) of {show.show_id}: the show's router shuts it "
                f"out within a second; no other certificate changes"
            )
            return 0
        if args.client is None:
            print(f"keys of {show.show_id} in {show.keys_dir}: " + (
                f"issued {', '.join(made)}" if made else "all present and valid"
            ))  # fmt: skip
            return 0
        folder = issue_client_folder(show, name, args.role)
    except (KeysError, OSError) as exc:
        print(f"skyquill keys: {exc}", file=sys.stderr)
        return 1
    print(f"client {name} ({args.role}) of {show.show_id}: {folder}")
    print(f"Zenoh config: {folder / 'zenoh-client.json5'} (copy the folder; the key is secret)")
    return 0

"""``skyquill keys SHOW.yaml``: the show's CA and one certificate per process; ``--client NAME
--role R`` issues a certificate for an outside client and writes a Zenoh config that uses it."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

NAME = "keys"
HELP = "Create the show's certificates (CA, one per process) or issue one to an outside client."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("show", type=Path, help="show file (YAML)")
    parser.add_argument("--client", metavar="NAME", help="issue a certificate to an outside client")
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


def run(args: argparse.Namespace) -> int:
    from showfile import ShowError, load_show
    from showfile.security import RESERVED_IDS
    from trust.hosts import endpoints
    from trust.pki import KeysError, client_files, issue
    from trust.settings import as_tls, ensure_show_keys, show_hosts

    try:
        show = load_show(args.show)
    except ShowError as exc:
        print(f"skyquill keys: {exc}", file=sys.stderr)
        return 2
    if show.security.mode == "none":
        print(f"skyquill keys: {args.show}: security is none: this show uses no keys")
        return 0
    try:
        made = ensure_show_keys(show)
        if args.client is None:
            print(f"keys of {show.show_id} in {show.keys_dir}: " + (
                f"issued {', '.join(made)}" if made else "all present and valid"
            ))  # fmt: skip
            return 0
        name = str(args.client)
        if not name.replace("-", "").replace("_", "").isalnum() or name in RESERVED_IDS:
            print(
                f"skyquill keys: --client {name!r}: use letters, digits, - and _", file=sys.stderr
            )
            return 2
        files = client_files(show.keys_dir, name, args.role)
        issue(show.keys_dir, files, show_id=show.show_id, hosts=show_hosts(show), holder=name)
    except (KeysError, OSError) as exc:
        print(f"skyquill keys: {exc}", file=sys.stderr)
        return 1
    config_path = files.cert.parent / "zenoh-client.json5"
    config = _client_config(list(as_tls(endpoints(show, "operator").connect)), files.cert.parent)
    config_path.write_text(json.dumps(config, indent=2) + "\n", encoding="utf-8")
    print(f"client {name} ({args.role}) of {show.show_id}: {files.cert.parent}")
    print(f"Zenoh config: {config_path} (copy the folder; the key is secret)")
    return 0

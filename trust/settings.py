"""The bus settings of one identity of a show: its certificate, the router's endpoints as TLS,
and, for the router, the generated access control.

Every process opens its session with ``open_session(session_settings(show, identity), ...)``.
With ``security: none`` the show's settings are returned unchanged and a warning is logged.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from bus.session import BusSettings
from showfile.bus_view import ShowBus
from showfile.roles import SERVICE_ROLES
from trust.acl import access_control
from trust.clients import load_clients, write_router_trust
from trust.files import IdentityFiles, KeysError, identity_files
from trust.hosts import all_endpoints, companion_routers, endpoints, is_router

log = logging.getLogger(__name__)

_warned: set[str] = set()


def _host(endpoint: str) -> str | None:
    """``tcp/10.0.0.2:7447`` -> ``10.0.0.2``; ``tls/[::1]:7447`` -> ``::1``."""
    _, _, address = endpoint.partition("/")
    host, _, _port = address.split("#", 1)[0].rpartition(":")
    return host.strip("[]") or None


def show_hosts(show: ShowBus) -> list[str]:
    """Host names and addresses the routers are reached at, for their certificates."""
    named = [_host(e) for e in all_endpoints(show)]
    hosts = [h for h in named if h and h not in ("0.0.0.0", "::")]
    return list(dict.fromkeys(hosts))


def as_tls(endpoints: Sequence[str]) -> tuple[str, ...]:
    """Endpoints with ``tcp/`` served as ``tls/`` (a secured show speaks TLS only)."""
    return tuple("tls/" + e[4:] if e.startswith("tcp/") else e for e in endpoints)


def identities(show: ShowBus) -> list[str]:
    """Every identity a show runs: the services, one per vehicle, one per companion router."""
    return [*SERVICE_ROLES, *(v.id for v in show.vehicles), *companion_routers(show)]


def ensure_show_keys(show: ShowBus) -> list[str]:
    """Create the show CA and any missing or stale identity; returns the identities (re)issued."""
    if show.security.mode == "none":
        return []
    from trust.pki import is_valid, issue  # cryptography: where keys are made

    issued = []
    hosts = show_hosts(show)
    for identity in identities(show):
        files = identity_files(show.keys_dir, identity)
        if not is_valid(files, hosts):
            issue(show.keys_dir, files, show_id=show.show_id, hosts=hosts)
            issued.append(identity)
    return issued


def check_keys(show: ShowBus, wanted: Sequence[str]) -> None:
    """Raise :class:`KeysError` unless every identity in ``wanted`` has valid files: a companion
    host never makes keys (it has no CA key); they are copied from the ground station."""
    if show.security.mode == "none":
        return
    from trust.pki import is_valid

    hosts = show_hosts(show)
    bad = [i for i in wanted if not is_valid(identity_files(show.keys_dir, i), hosts)]
    if bad:
        raise KeysError(
            f"{show.keys_dir}: no valid certificate for {', '.join(bad)}: copy ca.pem and the "
            f"folders {', '.join(bad)} from the ground station's keys folder (where `skyquill up "
            f"--host` of the ground station makes them)"
        )


def tls_section(files: IdentityFiles, *, trusted: Path | None = None) -> dict[str, Any]:
    """Zenoh ``transport/link/tls`` for an identity: mutual TLS against the show CA; a router
    (which serves) trusts ``trusted`` instead (the show CA and the admitted clients' issuers)."""
    router = trusted is not None
    section: dict[str, Any] = {
        "root_ca_certificate": str(trusted or files.ca),
        "enable_mtls": True,
        "verify_name_on_connect": True,
        "connect_private_key": str(files.key),
        "connect_certificate": str(files.cert),
    }
    if router:
        section["listen_private_key"] = str(files.key)
        section["listen_certificate"] = str(files.cert)
    return section


def secured(show: ShowBus, files: IdentityFiles, *, router: bool) -> BusSettings:
    """The show's bus settings for the identity in ``files``."""
    for path in (files.cert, files.key, files.ca):
        if not path.exists():
            raise KeysError(
                f"{path} is missing: create the show's keys with `skyquill keys "
                f"{show.source_path or show.show_id}` (or start it with `skyquill up`)"
            )
    z = show.zenoh
    where = endpoints(show, files.common_name)
    acl = trusted = None
    if router:
        clients = load_clients(show.keys_dir)
        vehicle_ids = [v.id for v in show.vehicles]
        acl = access_control(
            show.show_id, vehicle_ids, companion_routers(show), clients.common_names
        )
        trusted = write_router_trust(
            show.keys_dir, files.ca, clients, files.cert.parent / "trusted.pem"
        )
    return BusSettings(
        router_listen=as_tls(where.router_listen),
        connect=as_tls(where.connect),
        multicast_scouting=z.multicast_scouting,
        router_connect=as_tls(where.router_connect),
        peer_listen=as_tls(z.peer_listen),
        tls=tls_section(files, trusted=trusted),
        access_control=acl,
        extra=dict(z.extra),
        open_timeout_s=z.open_timeout_s,
    )


def plain(show: ShowBus, identity: str) -> Any:
    """Settings of ``security: none``: the show's own, or its host's endpoints."""
    if not show.zenoh.hosts:
        return show.zenoh
    where = endpoints(show, identity)
    z = show.zenoh
    return BusSettings(
        router_listen=where.router_listen,
        connect=where.connect,
        multicast_scouting=z.multicast_scouting,
        router_connect=where.router_connect,
        peer_listen=z.peer_listen,
        extra=dict(z.extra),
        open_timeout_s=z.open_timeout_s,
    )


def session_settings(show: ShowBus, identity: str) -> Any:
    """Settings for ``open_session`` of the process that is ``identity`` in ``show``."""
    if show.security.mode == "none":
        if show.show_id not in _warned:
            _warned.add(show.show_id)
            log.warning(
                "show %s runs with security: none: anyone who reaches its bus can command it",
                show.show_id,
            )
        return plain(show, identity)
    if identity not in identities(show):
        raise KeysError(f"{identity!r} is not an identity of show {show.show_id}")
    files = identity_files(show.keys_dir, identity)
    return secured(show, files, router=is_router(identity))


def client_session_settings(show: ShowBus, client_dir: Path) -> BusSettings:
    """Settings for an outside client holding the folder ``skyquill keys --client`` made;
    :class:`KeysError` for a folder issued before clients had names of their own."""
    from trust.pki import client_identity  # cryptography: reads the certificate's name

    folder = Path(client_dir)
    identity = client_identity(folder)
    files = IdentityFiles(identity, folder / "cert.pem", folder / "key.pem", folder / "ca.pem")
    return secured(show, files, router=False)

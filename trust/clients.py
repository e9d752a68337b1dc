"""The outside clients a show has issued and those it revoked: ``<keys_dir>/clients.json``.

An outside client (``skyquill keys SHOW --client NAME --role R``) has a certificate of its own,
whose common name is ``<role>@<name>`` (:func:`client_common_name`), signed by an issuer of its
own (``trust.pki.issue_client``). The access control gives each admitted client a subject of its
own with its role's rules, so two operators' laptops are two identities, and one can be shut out
alone. The router re-reads this list when it changes (``cli/cmd_router.py``) and trusts at
connection only the show CA and the issuers of the clients listed (:func:`write_router_trust`):
revoking a client removes it from the list, so its TLS handshake fails (it cannot connect) and
no rule would admit it anyway (default deny). Issuing a name again makes a new issuer: only the
newest certificate of a name is ever accepted. Light (no ``cryptography``): the router reads it
on every start.

Layout (written whole, then renamed into place, so a reader never sees half a file)::

    {"clients": {"booth": "submitter", "alice": "operator"}, "revoked": ["bob"]}
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from showfile.roles import CLIENT_ROLES
from trust.files import KeysError

__all__ = [
    "IssuedClients",
    "client_common_name",
    "client_issuer_path",
    "load_clients",
    "record_client",
    "registry_path",
    "revoke_client",
    "write_router_trust",
]

REGISTRY_NAME = "clients.json"


def client_common_name(name: str, role: str) -> str:
    """The identity of an outside client: ``operator@alice`` (``@`` is in no vehicle's or
    service's name, so a client never takes theirs)."""
    return f"{role}@{name}"


def client_issuer_path(keys_dir: Path, name: str) -> Path:
    """The certificate of the issuer of client ``name``'s certificate (``trust.pki``): the
    router trusts it while ``name`` is admitted."""
    return Path(keys_dir) / "clients" / name / "issuer.pem"


def registry_path(keys_dir: Path) -> Path:
    """Where a show's keys folder lists its outside clients."""
    return Path(keys_dir) / REGISTRY_NAME


@dataclass(frozen=True)
class IssuedClients:
    """The outside clients of a show."""

    roles: Mapping[str, str] = field(default_factory=dict)
    """Name -> role of every client the router admits."""
    revoked: frozenset[str] = frozenset()
    """Names revoked (and not issued again since): shut out, kept for the record."""

    @property
    def common_names(self) -> dict[str, str]:
        """Common name -> role of every admitted client, for the access control."""
        return {client_common_name(name, role): role for name, role in self.roles.items()}


def load_clients(keys_dir: Path) -> IssuedClients:
    """The registry (none yet: no clients); :class:`KeysError` if it cannot be read."""
    path = registry_path(keys_dir)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return IssuedClients()
    except (OSError, ValueError) as exc:
        raise KeysError(f"{path}: cannot read the show's clients: {exc}") from exc
    try:
        roles = dict(data["clients"])
        revoked = frozenset(data["revoked"])
        if not all(isinstance(n, str) and r in CLIENT_ROLES for n, r in roles.items()):
            raise ValueError("a client without a known role")
    except (KeyError, TypeError, ValueError) as exc:
        raise KeysError(f"{path}: not a list of the show's clients: {exc}") from exc
    return IssuedClients(roles, revoked)


def _write_whole(path: Path, data: bytes) -> None:
    """Write ``path`` (0600) under another name, then rename it into place."""
    partial = path.with_name(path.name + ".partial")
    fd = os.open(partial, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "wb") as out:
        out.write(data)
    os.replace(partial, path)


def _save(keys_dir: Path, clients: IssuedClients) -> None:
    data = {"clients": dict(sorted(clients.roles.items())), "revoked": sorted(clients.revoked)}
    _write_whole(registry_path(keys_dir), (json.dumps(data, indent=2) + "\n").encode())


def record_client(keys_dir: Path, name: str, role: str) -> None:
    """Admit ``name`` as a client of ``role`` (replacing its former role; a revoked name is
    admitted again with the new certificate its new issuer signed, never its old one)."""
    clients = load_clients(keys_dir)
    _save(keys_dir, IssuedClients({**clients.roles, name: role}, clients.revoked - {name}))


def revoke_client(keys_dir: Path, name: str) -> str:
    """Shut ``name`` out; returns its role. :class:`KeysError` if it is not a client of the
    show (or was revoked already)."""
    clients = load_clients(keys_dir)
    if name not in clients.roles:
        known = ", ".join(sorted(clients.roles)) or "none"
        already = " (revoked already)" if name in clients.revoked else ""
        raise KeysError(f"no client {name!r}{already}; the show's clients: {known}")
    roles = {n: r for n, r in clients.roles.items() if n != name}
    _save(keys_dir, IssuedClients(roles, clients.revoked | {name}))
    return clients.roles[name]


def write_router_trust(keys_dir: Path, show_ca: Path, clients: IssuedClients, out: Path) -> Path:
    """Write whom a router accepts at connection (PEM, for Zenoh's ``root_ca_certificate``):
    the show CA, then the issuer of every admitted client (one whose issuer is missing is left
    out: it cannot connect); returns ``out``."""
    try:
        parts = [show_ca.read_bytes()]
        for name in sorted(clients.roles):
            issuer = client_issuer_path(keys_dir, name)
            if issuer.exists():
                parts.append(issuer.read_bytes())
        _write_whole(out, b"".join(parts))
    except OSError as exc:
        raise KeysError(f"{out}: cannot write the router's trusted issuers: {exc}") from exc
    return out

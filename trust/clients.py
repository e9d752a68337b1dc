"""The outside clients a show has issued and those it revoked: ``<keys_dir>/clients.json``.

An outside client (``skyquill keys SHOW --client NAME --role R``) has a certificate of its own,
whose common name is ``<role>@<name>`` (:func:`client_common_name`): the access control gives
each issued client a subject of its own with its role's rules, so two operators' laptops are two
identities, and one can be shut out alone. The router admits only the clients listed here, and
re-reads the file when it changes (``cli/cmd_router.py``): revoking a client removes it from the
list (default deny: it can send and receive nothing) and keeps its name, which is never issued
again (its certificate would be admitted with it). Light (no ``cryptography``): the router reads
it on every start.

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
    "load_clients",
    "record_client",
    "registry_path",
    "revoke_client",
]

REGISTRY_NAME = "clients.json"


def client_common_name(name: str, role: str) -> str:
    """The identity of an outside client: ``operator@alice`` (``@`` is in no vehicle's or
    service's name, so a client never takes theirs)."""
    return f"{role}@{name}"


def registry_path(keys_dir: Path) -> Path:
    """Where a show's keys folder lists its outside clients."""
    return Path(keys_dir) / REGISTRY_NAME


@dataclass(frozen=True)
class IssuedClients:
    """The outside clients of a show."""

    roles: Mapping[str, str] = field(default_factory=dict)
    """Name -> role of every client the router admits."""
    revoked: frozenset[str] = frozenset()
    """Names revoked: shut out, and never issued again."""

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


def _save(keys_dir: Path, clients: IssuedClients) -> None:
    path = registry_path(keys_dir)
    data = {"clients": dict(sorted(clients.roles.items())), "revoked": sorted(clients.revoked)}
    partial = path.with_suffix(".json.partial")
    fd = os.open(partial, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w", encoding="utf-8") as out:
        out.write(json.dumps(data, indent=2) + "\n")
    os.replace(partial, path)


def record_client(keys_dir: Path, name: str, role: str) -> None:
    """List ``name`` as a client of ``role`` (replacing its former role); :class:`KeysError`
    if it was revoked."""
    clients = load_clients(keys_dir)
    if name in clients.revoked:
        raise KeysError(
            f"client {name!r} was revoked: its old certificate would be admitted again with "
            f"the name; issue the new one under another name"
        )
    _save(keys_dir, IssuedClients({**clients.roles, name: role}, clients.revoked))


def revoke_client(keys_dir: Path, name: str) -> str:
    """Shut ``name`` out for good; returns its role. :class:`KeysError` if it is not a client
    of the show (or was revoked already)."""
    clients = load_clients(keys_dir)
    if name not in clients.roles:
        known = ", ".join(sorted(clients.roles)) or "none"
        already = " (revoked already)" if name in clients.revoked else ""
        raise KeysError(f"no client {name!r}{already}; the show's clients: {known}")
    roles = {n: r for n, r in clients.roles.items() if n != name}
    _save(keys_dir, IssuedClients(roles, clients.revoked | {name}))
    return clients.roles[name]

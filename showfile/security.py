"""The show's ``security`` section: who may join its bus, and the names identities take."""

from __future__ import annotations

from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict

ServiceRole = Literal["router", "orchestrator", "kiosk", "operator"]
"""Identities of the processes ``skyquill up`` runs, besides one agent per vehicle."""

ClientRole = Literal["operator", "watcher", "submitter"]
"""Roles an operator hands to outside clients (``skyquill keys SHOW --client NAME --role R``)."""

SERVICE_ROLES: tuple[ServiceRole, ...] = ("router", "orchestrator", "kiosk", "operator")
CLIENT_ROLES: tuple[ClientRole, ...] = ("operator", "watcher", "submitter")

RESERVED_IDS = frozenset({*SERVICE_ROLES, *CLIENT_ROLES, "ca", "clients"})
"""Names no vehicle may take: they are certificate common names of roles, or key folders."""


class SecuritySettings(BaseModel):
    """How the show's processes prove who they are (see docs/protocol.md, "Joining a show")."""

    model_config = ConfigDict(frozen=True, extra="forbid", use_attribute_docstrings=True)

    mode: Literal["mtls", "none"] = "mtls"
    """``mtls``: Zenoh mutual TLS with one certificate per process from the show's own CA, and
    access control generated from the show (default deny); ``none``: plain TCP, anyone on the
    network may do anything (throwaway loopback tests only; a warning is printed)."""
    keys_dir: Path | None = None
    """Where the CA, the certificates and their keys live; default ``out/<show_id>/keys``.
    Never commit it: the private keys are the show's authority."""

"""The show's ``security`` section: who may join its bus, and the names identities take."""

from __future__ import annotations

from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict

from showfile.roles import (
    CLIENT_ROLES,
    RESERVED_IDS,
    SERVICE_ROLES,
    ClientRole,
    ServiceRole,
)

__all__ = [
    "CLIENT_ROLES",
    "RESERVED_IDS",
    "SERVICE_ROLES",
    "ClientRole",
    "SecuritySettings",
    "ServiceRole",
]


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

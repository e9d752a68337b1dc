"""The show's ``security`` section: who may join its bus, and the names identities take."""

from __future__ import annotations

import ipaddress
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
    "on_loopback",
]


class SecuritySettings(BaseModel):
    """How the show's processes prove who they are (see docs/protocol.md, "Joining a show")."""

    model_config = ConfigDict(frozen=True, extra="forbid", use_attribute_docstrings=True)

    mode: Literal["mtls", "none"] = "mtls"
    """``mtls``: Zenoh mutual TLS with one certificate per process from the show's own CA, and
    access control generated from the show (default deny); ``none``: plain TCP, anyone who
    reaches the bus may do anything: throwaway loopback tests only (a show whose bus listens
    beyond loopback is refused; ``skyquill up`` says it in red)."""
    keys_dir: Path | None = None
    """Where the CA, the certificates and their keys live (relative: from the show file's folder);
    default ``keys`` beside ``storage.database`` (``out/<show_id>/keys`` for the shipped shows).
    Never commit it: the private keys are the show's authority."""


def on_loopback(endpoint: str) -> bool:
    """Whether a Zenoh endpoint (``tcp/127.0.0.1:7447``, ``tcp/[::1]:7447#iface=lo``) listens on
    this machine only: a loopback address or ``localhost``; any other name may reach a network."""
    address = endpoint.partition("/")[2].split("?", 1)[0].split("#", 1)[0]
    host = address.rpartition(":")[0].strip("[]")
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False

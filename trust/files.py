"""Where a show's identities keep their certificate and key (light: no ``cryptography``, so a
process that only opens its session does not load it; :mod:`trust.pki` makes and checks them)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from bus.session import SessionOpenError

__all__ = ["IdentityFiles", "KeysError", "identity_files"]


class KeysError(SessionOpenError):
    """The show's keys are missing, unreadable or not the show's (no session can be opened)."""


@dataclass(frozen=True)
class IdentityFiles:
    """Where one identity's certificate and key are."""

    common_name: str
    """The identity, as the router's access control sees it."""
    cert: Path
    """PEM certificate signed by the show CA."""
    key: Path
    """PEM private key (mode 0600)."""
    ca: Path
    """The show CA's certificate, to verify the other side."""


def identity_files(keys_dir: Path, identity: str) -> IdentityFiles:
    """Paths of a service's or vehicle's identity (they may not exist yet)."""
    folder = Path(keys_dir) / identity
    return IdentityFiles(
        identity, folder / "cert.pem", folder / "key.pem", Path(keys_dir) / "ca.pem"
    )

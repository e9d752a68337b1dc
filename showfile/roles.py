"""The names identities take on a show's bus (services, outside clients, reserved names).

Apart from :mod:`showfile.security` (a pydantic model) so that opening a session
(:mod:`trust.settings`) does not import pydantic.
"""

from __future__ import annotations

from typing import Literal

ServiceRole = Literal["router", "orchestrator", "kiosk", "operator", "crew"]
"""Identities of the processes ``skyquill up`` runs, besides one agent per vehicle (``crew``: the
kiosk's second session, which serves the crew page and may confirm sheets and batteries only)."""

ClientRole = Literal["operator", "watcher", "submitter"]
"""Roles an operator hands to outside clients (``skyquill keys SHOW --client NAME --role R``)."""

SERVICE_ROLES: tuple[ServiceRole, ...] = ("router", "orchestrator", "kiosk", "operator", "crew")
CLIENT_ROLES: tuple[ClientRole, ...] = ("operator", "watcher", "submitter")

RESERVED_IDS = frozenset({*SERVICE_ROLES, *CLIENT_ROLES, "ca", "clients"})
"""Names no vehicle may take: they are certificate common names of roles, or key folders."""

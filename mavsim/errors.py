"""The one exception root of the MAVLink vehicle simulator."""

from __future__ import annotations


class MavsimError(RuntimeError):
    """A simulated MAVLink vehicle cannot start or run (bad configuration, port in use)."""

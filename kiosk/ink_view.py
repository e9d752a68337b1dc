"""The ink a drone left, as the page draws it (pure): shared by a character's ticket
(``kiosk/jobs.py``) and each character of a phrase's (``kiosk/phrase_view.py``)."""

from __future__ import annotations

import base64
from typing import Any

from bus.messages import WrittenInk


def written_view(ink: WrittenInk | None) -> dict[str, Any] | None:
    """The ink picture for the page (drawn on a canvas as data; see docs/protocol.md)."""
    if ink is None:
        return None
    return {
        "format": ink.format,
        "width_px": ink.width_px,
        "height_px": ink.height_px,
        "extent_m_board": list(ink.extent_m_board),
        "bits": base64.b64encode(ink.bits).decode("ascii"),
    }

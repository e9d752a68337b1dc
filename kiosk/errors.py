"""Errors of the kiosk: one root, and the rejection a member of the public sees."""

from __future__ import annotations


class KioskError(Exception):
    """Root of every error raised by :mod:`kiosk`."""


class RejectedError(KioskError):
    """A request the kiosk refuses, with words for the public and a code for programs."""

    def __init__(
        self,
        code: str,
        message: str,
        *,
        status: int = 400,
        retry_after_s: float | None = None,
        stroke_index: int | None = None,
        point_index: int | None = None,
        flight_s: float | None = None,
    ) -> None:
        super().__init__(message)
        self.code = code
        """Stable machine-readable code, e.g. ``too_large``, ``rate_limited``, ``blocked_text``."""
        self.message = message
        """One or two plain sentences a visitor understands; never echoes blocked words."""
        self.status = status
        """HTTP status of the reply."""
        self.retry_after_s = retry_after_s
        """Seconds until trying again makes sense (rate limit, orchestrator away)."""
        self.stroke_index = stroke_index
        self.point_index = point_index
        self.flight_s = flight_s
        """``too_long``: how long the planned writing would take, [s] (the page says it)."""

    def to_json_dict(self) -> dict[str, object]:
        """The ``error`` object of an API reply."""
        out: dict[str, object] = {"code": self.code, "message": self.message}
        if self.retry_after_s is not None:
            out["retry_after_s"] = round(self.retry_after_s, 1)
        if self.stroke_index is not None:
            out["stroke_index"] = self.stroke_index
        if self.point_index is not None:
            out["point_index"] = self.point_index
        if self.flight_s is not None:
            out["flight_s"] = round(self.flight_s, 1)
        return out

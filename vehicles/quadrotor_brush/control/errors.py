"""The one exception root of the controllers."""

from __future__ import annotations


class ControlError(ValueError):
    """A controller parameter or input that cannot be used; the message names the field."""

    def __init__(self, message: str, *, field: str | None = None) -> None:
        self.message = message
        self.field = field
        super().__init__(f"field {field!r}: {message}" if field is not None else message)

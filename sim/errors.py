"""The one exception root of the simulator."""

from __future__ import annotations


class SimError(ValueError):
    """A simulator input or parameter that cannot be simulated; the message names the field.

    Subclasses ``ValueError`` so callers that only know the standard library can catch it.
    """

    def __init__(self, message: str, *, field: str | None = None) -> None:
        self.message = message
        self.field = field
        super().__init__(f"field {field!r}: {message}" if field is not None else message)

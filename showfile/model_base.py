"""What every model of a show file shares: frozen, no unknown field, attribute docstrings as
field descriptions; and the form of an id."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict

Identifier = str
"""The id of a board, vehicle or host: :data:`ID_PATTERN`."""

ID_PATTERN = r"^[A-Za-z0-9][A-Za-z0-9_.-]*$"
"""Letters, digits, ``_.-``; not starting with a punctuation mark."""


class ShowModel(BaseModel):
    """Base of every section of a show file."""

    model_config = ConfigDict(frozen=True, extra="forbid", use_attribute_docstrings=True)

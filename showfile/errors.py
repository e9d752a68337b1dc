"""The root of the show-file errors, in a module of its own so that a command catching it
(``skyquill status`` over :mod:`showfile.bus_view`) need not import the models and pydantic."""

from __future__ import annotations


class ShowError(Exception):
    """Root of the show-file errors."""

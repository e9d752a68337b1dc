"""The show's event log read from its database, read-only (``skyquill log``).

The orchestrator stores every event it publishes (``orchestrator/store.py``, table ``events``:
``time_s`` in Unix seconds, the Event as JSON) before it answers. This reader opens the file
read-only, so it can run beside a live show (SQLite's write-ahead log lets a reader see every
committed event while the orchestrator writes) or on a copy after it, and never creates,
migrates or locks anything.
"""

from __future__ import annotations

import sqlite3
from collections.abc import Iterator
from pathlib import Path

import msgspec

from bus.messages import Event

__all__ = ["EventLogError", "read_events"]

BATCH_ROWS = 1_000
"""Rows fetched at a time: a long show's log is streamed, never held whole."""

_decoder = msgspec.json.Decoder(Event)


class EventLogError(Exception):
    """The database cannot be read (missing, not a show's, damaged)."""


def read_events(path: Path, since_s: float | None = None) -> Iterator[Event]:
    """Every stored event, oldest first; with ``since_s`` (Unix seconds), those from then on."""
    if not Path(path).is_file():
        raise EventLogError(f"{path}: no show database here (has the show run on this machine?)")
    try:
        db = sqlite3.connect(f"{Path(path).resolve().as_uri()}?mode=ro", uri=True)
    except sqlite3.Error as exc:
        raise EventLogError(f"{path}: cannot open the show database: {exc}") from exc
    try:
        rows = db.execute(
            "SELECT data FROM events WHERE time_s >= ? ORDER BY id",
            (since_s if since_s is not None else float("-inf"),),
        )
        while batch := rows.fetchmany(BATCH_ROWS):
            for (data,) in batch:
                try:
                    yield _decoder.decode(data)
                except msgspec.DecodeError as exc:
                    raise EventLogError(f"{path}: a stored event cannot be read: {exc}") from exc
    except sqlite3.Error as exc:
        raise EventLogError(f"{path}: cannot read the event log: {exc}") from exc
    finally:
        db.close()

"""Room on the orchestrator's disk: new characters are refused before the disk is full, and a
reserve lets the show go on when it fills anyway.

The orchestrator stores every change before it answers (crash-only: a change it cannot store
stops it, and the supervisor restarts it from the database). On a full disk that would be every
change, and a restart cannot even open the database (SQLite's WAL index is a new file). So:

- a submission is refused first while the disk has less than ``storage.min_free_mb`` free: one
  clear line to the submitter (``storage_full``), nothing taken that could be lost;
- a reserve file (:class:`DiskReserve`, ``RESERVE_BYTES``) is kept beside the database: when a
  write finds the disk full anyway (another process filled it), the store gives the reserve up
  and writes again (``orchestrator/store.py``), so the jobs already taken go on to their end; the
  reserve is made again once the disk has room.
"""

from __future__ import annotations

import contextlib
import os
import shutil
from pathlib import Path

from bus.messages import ErrorInfo

RESERVE_BYTES = 32 * 1024**2
"""The reserve beside the database, [B]: at the ~9 MB an hour a show's database grows by
(``storage.database_budget_mb``'s note), hours of reports and events."""


def storage_full(database: Path, min_free_bytes: float) -> ErrorInfo | None:
    """Why a submission is refused for want of disk (None: there is room)."""
    if min_free_bytes <= 0:
        return None
    try:
        free_bytes = shutil.disk_usage(database.parent).free
    except OSError as exc:
        return ErrorInfo(code="storage_full", message=f"cannot tell the disk's room: {exc}")
    if free_bytes >= min_free_bytes:
        return None
    message = (
        f"the show's disk is full ({free_bytes / 1e6:.0f} MB free, {min_free_bytes / 1e6:.0f}"
        " MB needed): no new character is taken until room is made; try again later"
    )
    return ErrorInfo(code="storage_full", message=message)


class DiskReserve:
    """A file of ``size_bytes`` beside ``database``, given up when the disk is full."""

    def __init__(self, database: Path, size_bytes: int = RESERVE_BYTES) -> None:
        self.path = database.with_name(database.name + ".reserve")
        self.size_bytes = size_bytes

    @property
    def held(self) -> bool:
        return self.path.exists()

    def make(self, min_free_bytes: float = 0.0) -> bool:
        """Make the reserve if it is missing and the disk keeps ``min_free_bytes`` beside it;
        True if it is there now."""
        if self.held:
            return True
        try:
            if shutil.disk_usage(self.path.parent).free < self.size_bytes + min_free_bytes:
                return False
            fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        except OSError:
            return False
        try:
            os.posix_fallocate(fd, 0, self.size_bytes)
        except OSError:
            self.release()
            return False
        finally:
            os.close(fd)
        return True

    def release(self) -> bool:
        """Give the reserve up; True if there was one."""
        with contextlib.suppress(FileNotFoundError):
            self.path.unlink()
            return True
        return False

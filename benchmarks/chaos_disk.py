"""The chaos soak's full disk (``bench_chaos.py``): the show's folder on a disk of its own.

:class:`OwnDisk` mounts a tmpfs on the show's folder (database, logs, job folders, recordings), so
that it can be filled to the last byte for a while (:meth:`OwnDisk.full`) without touching the
machine's disk. Mounting needs root: :func:`unavailable` says why it cannot run (None: it can).
"""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
import subprocess
from collections.abc import Iterator
from pathlib import Path

TMPFS_BYTES = 2 * 1024**3
"""The show's own disk: room for a two-hour soak's database, logs, job folders and recordings
(about 0.3 GB measured for 32 show minutes)."""
BALLAST = ".ballast"


def unavailable() -> str | None:
    """Why the disk cannot be filled on this machine (None: it can)."""
    if os.geteuid() != 0:
        return "needs root (a tmpfs of its own for the show's folder)"
    if shutil.which("mount") is None:
        return "needs mount (Debian: mount)"
    return None


class OwnDisk:
    """A tmpfs mounted on ``folder`` for the life of the context (root)."""

    def __init__(self, folder: Path, size_bytes: int = TMPFS_BYTES) -> None:
        self.folder = folder
        self.size_bytes = size_bytes

    def __enter__(self) -> OwnDisk:
        self.folder.mkdir(parents=True, exist_ok=True)
        subprocess.run(
            ["mount", "-t", "tmpfs", "-o", f"size={self.size_bytes}", "tmpfs", str(self.folder)],
            check=True,
        )
        return self

    def __exit__(self, *_: object) -> None:
        subprocess.run(["umount", "--lazy", str(self.folder)], check=False)

    @contextlib.contextmanager
    def full(self) -> Iterator[int]:
        """Fill the disk to its last byte for the life of the context; yields the bytes taken."""
        ballast = self.folder / BALLAST
        taken = 0
        chunk = b"\0" * (1 << 20)
        try:
            with ballast.open("wb", buffering=0) as out:
                while True:
                    try:
                        taken += out.write(chunk)
                    except OSError as exc:
                        if exc.errno != errno.ENOSPC:
                            raise
                        break
                for size in (4096, 512, 1):  # the last partial pages
                    with contextlib.suppress(OSError):
                        while True:
                            taken += out.write(chunk[:size])
            yield taken
        finally:
            ballast.unlink(missing_ok=True)

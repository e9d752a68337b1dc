"""Keeping a show's MCAP recordings within their disk budget.

The recorder cuts the bus recording into parts (``bus.recorder``); each time one is finished the
orchestrator removes the show's oldest recordings, parts of earlier runs first, until the rest
fit ``storage.recordings_budget_mb``. The part just finished and the one just begun are kept.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path


def prune_recordings(
    directory: Path, show_id: str, budget_bytes: int, keep: Iterable[Path]
) -> list[Path]:
    """Remove ``show_id``'s oldest ``.mcap`` files in ``directory`` beyond ``budget_bytes``
    (those in ``keep`` are never removed, but counted); returns the removed files."""
    kept = {path.resolve() for path in keep}
    sized = []
    for path in directory.glob(f"{show_id}-*.mcap"):
        try:
            sized.append((path.stat().st_mtime, path.name, path, path.stat().st_size))
        except FileNotFoundError:
            continue
    total = sum(size for *_, size in sized)
    removed = []
    for *_, path, size in sorted(sized):  # oldest first
        if total <= budget_bytes:
            break
        if path.resolve() in kept:
            continue
        try:
            path.unlink()
        except FileNotFoundError:
            pass  # removed meanwhile
        except OSError:
            continue  # cannot be removed: it still takes its room
        total -= size
        removed.append(path)
    return removed

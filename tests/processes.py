"""Helpers of the tests that start processes."""

from __future__ import annotations

import os


def running(pid: int) -> bool:
    """Whether process ``pid`` still exists (a zombie counts)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True

"""``report.png`` of a flown job, drawn off the control loop.

The figure is the vehicle kind's report (``VehicleKind.report``, written by
``vehicles.picture.save_png``); :class:`PictureWorker` draws such figures in a background
thread, one at a time: while one is still being drawn, the next is skipped rather than queued,
so a slow renderer never piles up work or memory behind a busy vehicle.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable

log = logging.getLogger(__name__)

PICTURE_NAME = "report.png"
"""File name of the picture in a job's directory."""


class PictureWorker:
    """Draws pictures in a background thread, at most one at a time."""

    def __init__(self, name: str) -> None:
        self.name = name
        """Who the pictures are of (thread name, log lines)."""
        self._busy = threading.Lock()
        self._thread: threading.Thread | None = None

    def submit(self, draw: Callable[[], object]) -> bool:
        """Start ``draw()`` in a new thread; False (skipped) while the previous one still runs."""
        if not self._busy.acquire(blocking=False):
            log.info("%s: previous report still rendering; skipping this one", self.name)
            return False
        self._thread = threading.Thread(
            target=self._run, args=(draw,), name=f"report-{self.name}", daemon=True
        )
        self._thread.start()
        return True

    def _run(self, draw: Callable[[], object]) -> None:
        try:
            draw()
        except Exception:
            log.exception("%s: cannot draw the job report", self.name)
        finally:
            self._busy.release()

    def wait(self, timeout_s: float) -> bool:
        """Wait up to ``timeout_s`` for the picture being drawn; True when none is left."""
        thread = self._thread
        if thread is not None:
            thread.join(timeout_s)
            return not thread.is_alive()
        return True

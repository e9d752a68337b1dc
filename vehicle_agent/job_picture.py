"""``report.png`` of a flown job: drawn off the control loop, later when the machine is busy,
never skipped.

A finished job's picture is first an order (:class:`PictureOrder`: everything drawing it needs),
written as ``picture.order`` into the job's directory; ``report.png`` replaces it once drawn.
:class:`PictureWorker` draws the orders in one background thread of the planning worker (a
process apart from the agent's control loop, in the batch scheduling class), oldest first, at a
lower priority than the worker's planning. Its queue in memory holds at most
:data:`QUEUE_CAPACITY` directories; the orders beyond it wait on disk, and so do those that a
stopped agent left undrawn: from its first order on, the worker takes up every order of its
vehicle it finds on disk whenever its queue runs dry. Before, a picture asked for while another
was being drawn was dropped (212 of 445 jobs pictured in a 20-minute soak at time scale 4).

``python -m vehicle_agent.job_picture JOBS_DIR`` draws every order waiting there now (after a
show, for the orders that agents stopped before drawing).
"""

from __future__ import annotations

import contextlib
import logging
import os
import pickle
import sys
import threading
import time
from collections import deque
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from vehicle_agent.job_files import (
    COMPACT_PICTURE_COLOURS,
    COMPACT_PICTURE_DPI,
    FULL_PICTURE_DPI,
)
from vehicles.kind import FlownWriting, WritingPlan

log = logging.getLogger(__name__)

PICTURE_NAME = "report.png"
"""File name of the picture in a job's directory."""
ORDER_NAME = "picture.order"
"""File name of a picture's order in a job's directory, until the picture is drawn."""
FAILED_NAME = "picture.failed"
"""An order that could not be drawn, kept for inspection and never taken up again."""
QUEUE_CAPACITY = 64
"""Orders held in memory (directory names only); more wait on disk."""
PICTURE_NICE_STEP = 5
"""How many nice levels the drawing thread takes below the planning worker's (planning a job
comes before picturing one already flown; Linux gives each thread its own nice value)."""
BACKLOG_WARNING = 4
"""Orders waiting at which the worker first says that pictures fall behind (then at 8, 16...)."""


@dataclass(frozen=True)
class PictureOrder:
    """What drawing one job's picture needs, self-contained (pickled into its directory)."""

    kind: str
    """The vehicle's kind (``vehicles.registry``), whose report figure is drawn."""
    settings: Any
    """The kind's settings of the vehicle."""
    plan: WritingPlan
    """The job's plan (without its kind-specific ``detail``)."""
    flown: FlownWriting
    """What was flown, every tick."""
    title: str
    """The figure's heading."""
    compact: bool
    """A compact picture (1280 px palette PNG) rather than a full one (1920 px, full colour)."""


def write_order(job_dir: Path, order: PictureOrder) -> Path:
    """Write ``order`` into ``job_dir`` atomically; returns its path."""
    path = job_dir / ORDER_NAME
    partial = job_dir / f".{ORDER_NAME}.partial"
    partial.write_bytes(pickle.dumps(order, protocol=pickle.HIGHEST_PROTOCOL))
    os.replace(partial, path)
    return path


def draw_picture(job_dir: Path, order: PictureOrder) -> Path:
    """Draw ``order`` as ``report.png`` in ``job_dir`` (slow: about a second of CPU)."""
    from vehicles.picture import save_png
    from vehicles.registry import vehicle_kind

    figure = vehicle_kind(order.kind).report(order.plan, order.flown, order.settings, order.title)
    path = job_dir / PICTURE_NAME
    if order.compact:
        save_png(figure, path, dpi=COMPACT_PICTURE_DPI, colours=COMPACT_PICTURE_COLOURS)
    else:
        save_png(figure, path, dpi=FULL_PICTURE_DPI)
    return path


def draw_order(job_dir: Path) -> Path | None:
    """Draw the order waiting in ``job_dir`` and remove it; None when there is none (drawn or
    pruned meanwhile). An order that cannot be read or drawn is renamed ``picture.failed``
    (raises what drawing raised)."""
    order_path = job_dir / ORDER_NAME
    try:
        blob = order_path.read_bytes()
    except FileNotFoundError:
        return None
    try:
        picture = draw_picture(job_dir, pickle.loads(blob))
    except Exception:
        with contextlib.suppress(FileNotFoundError):
            os.replace(order_path, job_dir / FAILED_NAME)
        raise
    order_path.unlink(missing_ok=True)
    return picture


class PictureWorker:
    """Draws one vehicle's job pictures in a background thread, one at a time, every one."""

    def __init__(self, name: str, capacity: int = QUEUE_CAPACITY) -> None:
        self.name = name
        """The vehicle whose pictures these are (its job directories: ``*-<name>-*``)."""
        self.drawn = 0
        """Pictures drawn so far."""
        self._capacity = capacity
        self._queue: deque[Path] = deque()
        self._cond = threading.Condition()
        self._busy = False
        self._on_disk = False  # orders may wait on disk that are not in the queue
        self._jobs_dir: Path | None = None
        self._thread: threading.Thread | None = None
        self._warned_at = 0

    @property
    def waiting(self) -> int:
        """Orders not drawn yet that this worker knows of (the one being drawn included)."""
        with self._cond:
            return len(self._queue) + self._busy

    def submit(self, job_dir: Path, order: PictureOrder) -> None:
        """Write ``order`` into ``job_dir`` and queue it (it waits on disk when the queue is
        full); the first order starts the thread, which takes up orders left by earlier runs."""
        write_order(job_dir, order)
        with self._cond:
            if self._thread is None:
                self._jobs_dir, self._on_disk = job_dir.parent, True
                self._thread = threading.Thread(
                    target=self._run, name=f"pictures-{self.name}", daemon=True
                )
                self._thread.start()
            elif len(self._queue) < self._capacity:
                self._queue.append(job_dir)
            else:
                self._on_disk = True
            waiting = len(self._queue) + self._busy
            self._cond.notify_all()
        self._say_backlog(waiting)

    def wait(self, timeout_s: float) -> bool:
        """Wait up to ``timeout_s`` for every known order to be drawn; True when none is left."""
        with self._cond:
            return self._cond.wait_for(self._idle, timeout_s)

    def _idle(self) -> bool:
        return not self._queue and not self._busy and not self._on_disk

    def _run(self) -> None:
        with contextlib.suppress(OSError):  # a step down in priority is always allowed
            tid = threading.get_native_id()
            nice = os.getpriority(os.PRIO_PROCESS, tid)
            os.setpriority(os.PRIO_PROCESS, tid, nice + PICTURE_NICE_STEP)
        while True:
            with self._cond:
                while not self._queue:
                    if self._on_disk:
                        self._on_disk = False
                        self._queue.extend(self._orders_on_disk())
                        continue
                    self._busy = False
                    self._cond.notify_all()
                    self._cond.wait()
                job_dir = self._queue.popleft()
                self._busy = True
            self._draw(job_dir)

    def _orders_on_disk(self) -> list[Path]:
        """This vehicle's undrawn orders on disk, oldest first, as many as the queue holds
        (the rest are looked for again when these are drawn)."""
        assert self._jobs_dir is not None
        found = []
        for path in self._jobs_dir.glob(f"*-{self.name}-*/{ORDER_NAME}"):
            with contextlib.suppress(FileNotFoundError):
                found.append((path.stat().st_mtime, path.parent))
        found.sort()
        if len(found) > self._capacity:
            self._on_disk = True
        return [job_dir for _, job_dir in found[: self._capacity]]

    def _draw(self, job_dir: Path) -> None:
        started_s = time.thread_time()
        try:
            picture = draw_order(job_dir)
        except Exception:
            log.exception("%s: cannot draw the picture of %s", self.name, job_dir.name)
            return
        if picture is not None:
            self.drawn += 1
            cpu_s = time.thread_time() - started_s
            log.debug("%s: drew %s in %.2f s of CPU", self.name, picture, cpu_s)

    def _say_backlog(self, waiting: int) -> None:
        """Warn when the backlog reaches 4, 8, 16... pictures (once per level until it drains)."""
        if waiting <= 1:
            self._warned_at = 0
        elif waiting >= BACKLOG_WARNING and waiting >= 2 * self._warned_at:
            self._warned_at = waiting
            log.warning(
                "%s: %d job pictures wait to be drawn (the machine is busy); each will be drawn",
                self.name,
                waiting,
            )


def main(argv: list[str]) -> int:
    """Draw every order waiting in the job directories under ``argv[0]``, oldest first."""
    if len(argv) != 1 or not Path(argv[0]).is_dir():
        print("usage: python -m vehicle_agent.job_picture JOBS_DIR", file=sys.stderr)
        return 2
    orders = sorted(Path(argv[0]).glob(f"*/{ORDER_NAME}"), key=lambda p: p.stat().st_mtime)
    failed = 0
    for order in orders:
        try:
            print(draw_order(order.parent))
        except Exception as exc:
            print(f"{order.parent.name}: cannot draw its picture: {exc}", file=sys.stderr)
            failed += 1
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

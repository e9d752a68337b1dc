"""``report.png`` of a flown job: drawn off the control loop, later when the machine is busy,
never skipped.

A finished job's picture is first an order (:class:`PictureOrder`: everything drawing it needs),
written as ``picture.order`` into the job's directory; ``report.png`` replaces it once drawn.
:class:`PictureWorker` draws the orders from one background thread of the planning worker (a
process apart from the agent's control loop, in the batch scheduling class), oldest first, at a
lower priority than the worker's planning, each batch in a short-lived drawing process
(:mod:`vehicle_agent.picture_process`: matplotlib stays out of the worker, issue 35). Its queue
in memory holds at most :data:`QUEUE_CAPACITY` directories; the orders beyond it wait on disk,
and so do those that a stopped agent left undrawn: from its first order on, the worker takes up
every order of its vehicle it finds on disk whenever its queue runs dry. Before, a picture asked
for while another was being drawn was dropped (212 of 445 jobs pictured in a 20-minute soak at
time scale 4).

``python -m vehicle_agent.job_picture JOBS_DIR`` draws every order waiting there now (after a
show, for the orders that agents stopped before drawing); ``--each JOB_DIR...`` is the drawing
process's own command.
"""

from __future__ import annotations

import contextlib
import logging
import os
import pickle
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from vehicle_agent.job_files import (
    COMPACT_PICTURE_COLOURS,
    COMPACT_PICTURE_DPI,
    FULL_PICTURE_DPI,
)
from vehicle_agent.picture_process import (
    CPU,
    DRAWING,
    DRAWN,
    FAILED,
    GONE,
    BatchOutcome,
    die_with_parent,
    draw_apart,
    drawing_turn,
    say,
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
comes before picturing one already flown; Linux gives each thread its own nice value, and the
drawing processes it starts inherit it)."""
BACKLOG_WARNING = 4
"""Orders waiting at which the worker first says that pictures fall behind (then at 8, 16...)."""
DRAW_BATCH = 8
"""Orders one drawing process draws at most before it exits: its start (interpreter, numpy,
pydantic, matplotlib: about 1 s of CPU) is shared by a backlog, and its memory (matplotlib's,
with a figure) is held for a few pictures at a time, not for the show."""
RETRY_AFTER_S = 10.0
"""Wall time in [s] before a drawing process is started again after one got nowhere (it could
not start, or died before its first order): the orders wait on disk meanwhile."""


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
    """Draws one vehicle's job pictures, every one: a background thread hands the orders, a
    batch at a time, to a drawing process apart (:func:`vehicle_agent.picture_process.draw_apart`)
    that takes the thread's lower priority and exits with its batch."""

    def __init__(self, name: str, capacity: int = QUEUE_CAPACITY) -> None:
        self.name = name
        """The vehicle whose pictures these are (its job directories: ``*-<name>-*``)."""
        self.drawn = 0
        """Pictures drawn so far."""
        self.drawing_cpu_s = 0.0
        """CPU time in [s] of the drawing processes so far (their imports included)."""
        self._capacity = capacity
        self._queue: dict[Path, None] = {}  # in order, each directory once
        self._drawing: list[Path] = []
        self._cond = threading.Condition()
        self._on_disk = False  # orders may wait on disk that are not in the queue
        self._jobs_dir: Path | None = None
        self._thread: threading.Thread | None = None
        self._warned_at = 0

    @property
    def waiting(self) -> int:
        """Orders not drawn yet that this worker knows of (those being drawn included)."""
        with self._cond:
            return self._known()

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
            elif job_dir not in self._queue and job_dir not in self._drawing:
                if len(self._queue) < self._capacity:
                    self._queue[job_dir] = None
                else:
                    self._on_disk = True
            waiting = self._known()
            self._cond.notify_all()
        self._say_backlog(waiting)

    def wait(self, timeout_s: float) -> bool:
        """Wait up to ``timeout_s`` for every known order to be drawn; True when none is left."""
        with self._cond:
            return self._cond.wait_for(self._idle, timeout_s)

    def _known(self) -> int:
        return len(self._queue) + len(self._drawing)

    def _idle(self) -> bool:
        return not self._queue and not self._drawing and not self._on_disk

    def _run(self) -> None:
        with contextlib.suppress(OSError):  # a step down in priority is always allowed
            tid = threading.get_native_id()
            nice = os.getpriority(os.PRIO_PROCESS, tid)
            os.setpriority(os.PRIO_PROCESS, tid, nice + PICTURE_NICE_STEP)
        while True:
            with self._cond:
                self._drawing = []
                while not self._queue:
                    if self._on_disk:
                        self._on_disk = False
                        for job_dir in self._orders_on_disk():
                            self._queue.setdefault(job_dir)
                        continue
                    self._cond.notify_all()
                    self._cond.wait()
                assert self._jobs_dir is not None
            with drawing_turn(self._jobs_dir):  # what waits meanwhile joins this batch
                with self._cond:
                    self._drawing = list(self._queue)[:DRAW_BATCH]
                    for job_dir in self._drawing:
                        del self._queue[job_dir]
                got_somewhere = self._draw(self._drawing)
            if not got_somewhere:
                time.sleep(RETRY_AFTER_S)

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

    def _draw(self, batch: list[Path]) -> bool:
        """Draw ``batch`` in a process apart; False when no drawing process got anywhere
        (its orders stay on disk, taken up again after :data:`RETRY_AFTER_S`)."""
        try:
            outcome = draw_apart(batch)
        except OSError as exc:
            log.error("%s: cannot start drawing pictures: %s", self.name, exc)
            outcome = BatchOutcome(not_reached=batch)
        self.drawn += len(outcome.drawn)
        self.drawing_cpu_s += outcome.cpu_s or 0.0
        for job_dir, reason in outcome.failed:
            log.error("%s: cannot draw the picture of %s: %s", self.name, job_dir.name, reason)
        if outcome.died_on is not None:  # what killed the child would kill the next one
            with contextlib.suppress(FileNotFoundError):
                os.replace(outcome.died_on / ORDER_NAME, outcome.died_on / FAILED_NAME)
            log.error(
                "%s: the drawing process died (code %s) on the picture of %s; set aside",
                self.name,
                outcome.exit_code,
                outcome.died_on.name,
            )
        if outcome.not_reached:
            with self._cond:
                self._on_disk = True
        return len(outcome.not_reached) < len(batch)

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


def draw_each(job_dirs: list[str]) -> int:
    """The drawing process's work (``--each``): draw the orders of ``job_dirs`` in turn and
    say what became of each on stdout (:mod:`vehicle_agent.picture_process`)."""
    die_with_parent()
    for text in job_dirs:
        say(DRAWING, text)
        try:
            picture = draw_order(Path(text))
        except Exception as exc:
            say(FAILED, text, f"{type(exc).__name__}: {exc}")
        else:
            say(GONE if picture is None else DRAWN, text)
    say(CPU, f"{time.process_time():.3f}")
    return 0


def main(argv: list[str]) -> int:
    """Draw every order waiting in the job directories under ``argv[0]``, oldest first."""
    if argv[:1] == ["--each"]:
        return draw_each(argv[1:])
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

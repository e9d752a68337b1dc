"""Job pictures drawn in a short-lived process apart (``python -m vehicle_agent.job_picture
--each JOB_DIR...``), so that matplotlib never enters the long-lived planning worker.

Drawn in the worker's own thread (before), a picture left matplotlib, its fonts and caches in
the worker for the rest of the show, 60-70 MiB per worker on top of what planning needs (issue
35: 204-231 MiB per worker, four of them). A drawing process lives for one batch of orders and
its memory goes back to the system when it exits; one runs at a time per host
(:func:`drawing_turn`).

The child says what it does, one line per event on its stdout (:data:`DRAWING`, then
:data:`DRAWN`, :data:`GONE` or :data:`FAILED` with the reason); the parent reads them as they
come, so it knows which order a crashed child was drawing (:attr:`BatchOutcome.died_on`) and
which it never reached (:attr:`BatchOutcome.not_reached`).
"""

from __future__ import annotations

import contextlib
import ctypes
import fcntl
import os
import signal
import subprocess
import sys
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

DRAWING = "drawing"
"""Line word: the child starts the order of this directory."""
DRAWN = "drawn"
"""Line word: its picture is drawn and its order removed."""
GONE = "gone"
"""Line word: no order was there any more (drawn or pruned meanwhile)."""
FAILED = "failed"
"""Line word: it could not be drawn (set aside as ``picture.failed``), the reason after a tab."""
CPU = "cpu"
"""Last line: the child's CPU time in [s], imports included."""
TURN_NAME = ".drawing.lock"
"""The lock file in a show's jobs directory whose holder may run a drawing process."""
PR_SET_PDEATHSIG = 1
ROOT = Path(__file__).resolve().parent.parent
"""The checkout, put first on the child's ``PYTHONPATH`` (it imports this very code)."""


@dataclass
class BatchOutcome:
    """What a drawing process did with its batch of job directories."""

    drawn: list[Path] = field(default_factory=list)
    gone: list[Path] = field(default_factory=list)
    failed: list[tuple[Path, str]] = field(default_factory=list)
    """Orders that could not be drawn, with the child's reason (the child set them aside)."""
    died_on: Path | None = None
    """The order being drawn when the child died (None: it did not die drawing)."""
    not_reached: list[Path] = field(default_factory=list)
    """Orders the child never started (it died before)."""
    exit_code: int | None = None
    cpu_s: float | None = None
    """The child's CPU time in [s] (None: it did not say)."""


@contextlib.contextmanager
def drawing_turn(jobs_dir: Path) -> Iterator[None]:
    """Wait for the show's turn to draw (an exclusive ``flock`` on :data:`TURN_NAME` in
    ``jobs_dir``, which every vehicle's jobs share on a host) and hold it inside the block.

    One drawing process at a time for all the agents of a host: a drawing process holds 95-125
    MiB while it lives (matplotlib, a figure), 20 s of wall time at load 7; four of them at once,
    one per vehicle, put the Airshow back over its 1 GiB (issue 35). Drawing them side by side
    would not finish them sooner on the two cores they share with the control loops, and the
    orders that wait meanwhile are drawn by the next process, several per process."""
    with open(jobs_dir / TURN_NAME, "a+b") as turn:
        fcntl.flock(turn, fcntl.LOCK_EX)  # released when closed, or when this process dies
        yield


def draw_apart(job_dirs: Sequence[Path]) -> BatchOutcome:
    """Draw the orders of ``job_dirs`` in a child process, in this order; returns what it did
    (raises OSError when no process can be started). The child takes this thread's priority."""
    command = [sys.executable, "-m", "vehicle_agent.job_picture", "--each", *map(str, job_dirs)]
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH", "")) if p)
    outcome, started = BatchOutcome(), set()
    with subprocess.Popen(
        command, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, text=True, env=env
    ) as child:
        assert child.stdout is not None
        for line in child.stdout:
            word, _, rest = line.rstrip("\n").partition("\t")
            path_text, _, reason = rest.partition("\t")
            path = Path(path_text)
            if word == DRAWING:
                outcome.died_on = path
                started.add(path)
            elif word in (DRAWN, GONE, FAILED):
                outcome.died_on = None
                if word == DRAWN:
                    outcome.drawn.append(path)
                elif word == GONE:
                    outcome.gone.append(path)
                else:
                    outcome.failed.append((path, reason))
            elif word == CPU:
                outcome.cpu_s = float(path_text)
    outcome.exit_code = child.returncode
    if outcome.exit_code != 0:
        outcome.not_reached = [d for d in job_dirs if d not in started]
    else:
        outcome.died_on = None
    return outcome


def say(word: str, subject: Path | str, reason: str = "") -> None:
    """The child's line: ``word``, a job directory (or the CPU time) and a reason on one line,
    flushed at once (the parent learns what this child did even if it dies next)."""
    text = f"{word}\t{subject}" + (f"\t{' '.join(reason.split())}" if reason else "")
    print(text, flush=True)


def die_with_parent() -> None:
    """In the child: be killed with the planning worker (its orders stay on disk)."""
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL)

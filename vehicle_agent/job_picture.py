"""``report.png`` of a flown job, drawn off the control loop.

:func:`job_figure` is the report figure of :mod:`vehicle_agent.report` (as ``skyquill fly`` draws
it) for one job an agent flew; :class:`PictureWorker` draws such figures in a background thread,
one at a time: while one is still being drawn, the next is skipped rather than queued, so a slow
renderer never piles up work or memory behind a busy vehicle.
"""

from __future__ import annotations

import logging
import os
import threading
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from planner.board import BoardFrame
from planner.samples import TrajectorySamples
from vehicle_agent.flight import FlightLog
from vehicle_agent.metrics import flight_metrics, ink_result
from vehicle_agent.report import build_report, save_report

log = logging.getLogger(__name__)

PICTURE_NAME = "report.png"
"""File name of the picture in a job's directory."""


def _reference_velocity(samples: TrajectorySamples, t_s: np.ndarray) -> np.ndarray:
    """The planned velocity at the trace's instants (time since writing started), (K, 1, 3)."""
    axes = [np.interp(t_s, samples.t_s, samples.velocity_mps_enu[:, c]) for c in range(3)]
    return np.stack(axes, axis=1)[:, None, :]


def job_figure(
    flight: FlightLog,
    samples: TrajectorySamples,
    strokes_board_m: tuple[np.ndarray, ...] | None,
    board: BoardFrame,
    *,
    pixel_m: float,
    title: str,
) -> Figure:
    """The report figure of one flown job: ``flight`` as the agent recorded it, ``samples`` its
    planned reference, ``strokes_board_m`` the glyph as laid out on ``board`` (drawn in world
    x/y); metrics and ink as the agent measures them (``pixel_m``)."""
    flight = replace(flight, reference_velocity_mps_enu=_reference_velocity(samples, flight.t_s))
    ink = ink_result(flight, pixel_m=pixel_m)
    scores = flight_metrics(flight, ink=ink)
    strokes_xy = (
        [board.to_world(np.asarray(s, dtype=np.float64))[:, :2] for s in strokes_board_m]
        if strokes_board_m
        else None
    )
    return build_report(flight, scores, ink, input_strokes_xy_m=strokes_xy, title=title)


def save_png(figure: Figure, path: Path) -> None:
    """Write the figure as PNG atomically (a reader never sees half a file)."""
    partial = path.with_name(f".{path.name}.partial")
    save_report(figure, partial)
    os.replace(partial, path)


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

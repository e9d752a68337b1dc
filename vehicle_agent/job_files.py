"""A vehicle's job directories on disk: how detailed they are, and keeping them within budget.

Each flown job leaves ``<database dir>/jobs/<job>-<vehicle>-<attempt>/``: ``metrics.json``, the
planned reference, what was flown and ``report.png``. ``compact`` (the default) keeps a job
under about 100 kB: the reference and the flight at ``COMPACT_RATE_HZ`` in float32 in one
compressed ``flight.npz``, a palette picture; ``full`` keeps every tick (``TRAJ.json`` beside) and a
full-size picture, for engineers tuning a vehicle. ``flight.npz`` holds the job's trace in the
kinds' format under its field names (``vehicle_agent.jobs.flight_arrays``).

Every agent prunes only its own vehicle's directories (agents of one show may share the folder,
and on several hosts each has its own), oldest first, down to its share of the show's budget and
its age limit. Job records in the orchestrator's database are never touched: only files.
"""

from __future__ import annotations

import json
import shutil
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Literal

import numpy as np

if TYPE_CHECKING:  # a drawing process imports this module; the show file's models cost 0.2 s
    from showfile import Show

COMPACT_RATE_HZ = 20.0
"""Rate in [Hz] of the flight kept in a compact job directory."""
COMPACT_PICTURE_DPI = 100.0
"""Resolution in [dots/in] of a compact ``report.png``: the kinds' figures are 12.8 in wide
(``vehicles.picture``), so 1280 px, type 14-18 px high (36 dpi drew 540 px and 5 px type)."""
COMPACT_PICTURE_COLOURS = 32
"""Colours of a compact ``report.png``, a palette PNG of lines drawn without anti-aliasing (text
keeps it): a fifth of the bytes of full colour (a brush job's 1280 px picture ~40 kB against
~235 kB), every line colour kept, so that a job stays under 100 kB."""
FULL_PICTURE_DPI = 150.0
"""Resolution in [dots/in] of a full ``report.png`` (full colour, 1920 px)."""


@dataclass(frozen=True)
class JobFilesPolicy:
    """How a vehicle keeps its job directories."""

    detail: Literal["compact", "full"] = "compact"
    """How much of a job is kept."""
    budget_bytes: int = 100_000_000
    """This vehicle's share of the show's budget, in bytes."""
    max_age_s: float | None = None
    """Directories older than this are removed, in [s]; None: no age limit."""

    @property
    def compact(self) -> bool:
        return self.detail == "compact"

    @classmethod
    def of(cls, show: Show) -> JobFilesPolicy:
        """The show's ``storage`` settings, the budget shared evenly by its vehicles."""
        storage = show.storage
        share = storage.job_files_budget_mb * 1e6 / max(1, len(show.vehicles))
        age_h = storage.job_files_max_age_h
        return cls(storage.job_files, int(share), None if age_h is None else age_h * 3600.0)


def decimated(t_s: np.ndarray, rate_hz: float) -> np.ndarray:
    """Indices of samples at most ``rate_hz`` apart in time, the first and last kept."""
    if t_s.size == 0:
        return np.arange(0)
    slots = np.floor((t_s - t_s[0]) * rate_hz + 1e-9).astype(np.int64)
    first = np.flatnonzero(np.diff(slots, prepend=-1) > 0)
    return np.unique(np.append(first, t_s.size - 1))


def compact_arrays(
    arrays: dict[str, np.ndarray], t_s: np.ndarray, prefix: str = ""
) -> dict[str, np.ndarray]:
    """Per-tick arrays at ``COMPACT_RATE_HZ``, named ``prefix + name``, floats as float32
    (0.1 mm at 1 km) but time (``t_s``: float32 steps reach milliseconds in hours of show)."""
    keep = decimated(t_s, COMPACT_RATE_HZ)
    out: dict[str, np.ndarray] = {}
    for name, value in arrays.items():
        part = value[keep] if value.shape[:1] == t_s.shape else value
        narrow = part.dtype == np.float64 and name != "t_s"
        out[prefix + name] = part.astype(np.float32) if narrow else part
    return out


def written_whole(job_dir: Path) -> bool:
    """Whether a job directory holds an attempt flown to its end: its ``metrics.json`` names no
    reason it was broken off (``abort_reason``: a safety abort, a cancel, a land, an emergency
    stop, a fault, a lease given up, ``vehicle_agent/end_reasons.py``); False when it has none or
    it cannot be read (a directory being written)."""
    try:
        summary = json.loads((job_dir / "metrics.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    return isinstance(summary, dict) and summary.get("abort_reason") is None


def directory_bytes(path: Path) -> int:
    return sum(f.stat().st_size for f in path.iterdir() if f.is_file())


def prune(
    jobs_dir: Path, vehicle_id: str, policy: JobFilesPolicy, now_s: float | None = None
) -> list[Path]:
    """Remove this vehicle's oldest job directories beyond its budget or age; returns them."""
    now = time.time() if now_s is None else now_s
    mine = [d for d in jobs_dir.glob(f"*-{vehicle_id}-*") if d.is_dir()]
    aged = sorted(mine, key=lambda d: d.stat().st_mtime, reverse=True)  # newest first
    removed, total = [], 0
    for i, path in enumerate(aged):
        try:
            size, age_s = directory_bytes(path), now - path.stat().st_mtime
        except FileNotFoundError:
            continue
        total += size
        too_old = policy.max_age_s is not None and age_s > policy.max_age_s
        if i > 0 and (total > policy.budget_bytes or too_old):  # never the job just written
            shutil.rmtree(path, ignore_errors=True)
            removed.append(path)
    return removed

"""One job replayed from its files as a Foxglove recording, for a tuning engineer.

A flown job's directory (``<database dir>/jobs/<job>-<vehicle>-<attempt>/``, written by the
vehicle agent) holds ``metrics.json`` and ``flight.npz``: what was flown at 20 Hz (compact) or
every tick (full), with the reference it followed and the plan. :func:`replay_job` feeds that
flight, sample by sample, through the same scene as a live show (:class:`ShowScene`), adds the
whole plan as a line from the first instant and the metrics as a log line, and writes one MCAP.
The vehicle's frame is at its reference point (``base_m_enu`` where the files keep one, else the
writing point), its writing point below it; the files keep no attitude, so the frame keeps the
world's axes.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import foxglove.messages as fg
import numpy as np
from mcap.writer import CompressionType, Writer

from bus.mcap_channels import DerivedMessage, McapChannels
from bus.messages import Telemetry
from scene.encode import encoded, timestamp
from scene.show_scene import LOG_TOPIC, PATHS_TOPIC, ShowScene
from scene.vehicles import JobPaths
from showfile import Show


class ReplayError(ValueError):
    """A job that cannot be replayed: the message says which and why, in one line."""


@dataclass(frozen=True)
class JobFolder:
    """One flown attempt of a job on disk."""

    path: Path
    job_id: str
    vehicle_id: str
    attempt: int


def job_folders(show: Show, job_id: str) -> list[JobFolder]:
    """Every attempt of ``job_id`` kept on disk, oldest attempt first; :class:`ReplayError` when
    none is (naming the folder looked in and a few jobs it holds)."""
    jobs_dir = show.database_path.parent / "jobs"
    found = []
    for path in jobs_dir.glob(f"{job_id}-*-*"):
        try:
            summary = json.loads((path / "metrics.json").read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue
        if summary.get("job_id") == job_id:
            found.append(JobFolder(path, job_id, summary["vehicle_id"], int(summary["attempt"])))
    if not found:
        kept = sorted({p.name.rsplit("-", 2)[0] for p in jobs_dir.glob("*-*-*") if p.is_dir()})
        hint = f"; jobs kept there: {', '.join(kept[-5:])}" if kept else " (no job kept there)"
        raise ReplayError(f"no files of job {job_id!r} in {jobs_dir}{hint}")
    return sorted(found, key=lambda f: f.attempt)


def replay_job(show: Show, folder: JobFolder, out: Path, *, start_ns: int) -> int:
    """Write ``folder``'s flight as a Foxglove MCAP to ``out``; returns the messages written."""
    with np.load(folder.path / "flight.npz", allow_pickle=False) as npz:
        flight = {name: npz[name] for name in npz.files}
    summary = json.loads((folder.path / "metrics.json").read_text(encoding="utf-8"))
    count = 0
    with out.open("wb") as f:
        writer = Writer(f, compression=CompressionType.ZSTD)
        writer.start(profile="", library="skyquill replay")
        channels = McapChannels(writer)
        for stamp_ns, message in _messages(show, folder, flight, summary, start_ns):
            channels.add(message, stamp_ns, count)
            count += 1
        writer.finish()  # type: ignore[no-untyped-call]
    return count


def _messages(
    show: Show, folder: JobFolder, flight: dict[str, Any], summary: dict[str, Any], start_ns: int
) -> Iterator[tuple[int, DerivedMessage]]:
    scene = ShowScene(show)
    t_s = np.asarray(flight["t_s"], dtype=float)
    if t_s.size == 0:
        raise ReplayError(f"{folder.path}: flight.npz holds no sample")
    point = np.asarray(flight["writing_point_m_enu"], dtype=float)
    base = np.asarray(flight.get("base_m_enu", point), dtype=float)
    reference = np.asarray(flight.get("reference_m_enu", base), dtype=float)
    pen_down = np.asarray(flight.get("pen_down", np.zeros(t_s.size, bool)), dtype=bool)
    force = flight.get("force_n")
    yield start_ns, encoded(PATHS_TOPIC, _plan(folder, flight, reference, start_ns))
    for i in range(t_s.size):
        stamp_ns = start_ns + round((t_s[i] - t_s[0]) * 1e9)
        sample = Telemetry(
            vehicle_id=folder.vehicle_id,
            t_s=float(t_s[i]),
            state="writing",
            position_m_enu=_xyz(base[i]),
            velocity_mps_enu=(0.0, 0.0, 0.0),
            reference_m_enu=_xyz(reference[i]),
            pen_down=bool(pen_down[i]),
            tracking_error_m=float(np.linalg.norm(base[i] - reference[i])),
            job_id=folder.job_id,
            progress=(i + 1) / t_s.size,
            force_n=None if force is None or not math.isfinite(force[i]) else float(force[i]),
            writing_point_m_enu=_xyz(point[i]),
        )
        for message in scene.fixed(stamp_ns):
            yield stamp_ns, message
        for message in scene.telemetry(sample, stamp_ns):
            yield stamp_ns, message
    end_ns = start_ns + round((t_s[-1] - t_s[0]) * 1e9)
    line = fg.Log(
        timestamp=timestamp(end_ns),
        level=fg.LogLevel.Info,
        message=f"job {folder.job_id} on {folder.vehicle_id}, attempt {folder.attempt}: "
        + json.dumps(summary.get("metrics"), sort_keys=True),
        name="metrics",
    )
    yield end_ns, encoded(LOG_TOPIC, line)


def _plan(
    folder: JobFolder, flight: dict[str, Any], reference: np.ndarray, stamp_ns: int
) -> fg.SceneUpdate:
    """The whole plan as one line (the compact files' ``reference_position_m_enu``; else the
    reference the vehicle followed)."""
    plan = np.asarray(flight.get("reference_position_m_enu", reference), dtype=float)
    paths = JobPaths(job_id=folder.job_id, planned=[_xyz(p) for p in plan])
    return fg.SceneUpdate(entities=[paths.entity(f"{folder.vehicle_id}/plan", stamp_ns)])


def _xyz(v: np.ndarray) -> tuple[float, float, float]:
    return float(v[0]), float(v[1]), float(v[2])

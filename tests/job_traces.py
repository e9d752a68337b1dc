"""Flown jobs made up for tests, recorded as the agent records them: one snapshot and setpoint
per row through :class:`vehicle_agent.trace.TraceRecorder`."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from bus.messages import JobAssignment
from showfile import load_show
from vehicle_agent.backends.base import Setpoint, Vec3, VehicleSnapshot
from vehicle_agent.jobs import PreparedJob, prepare_job
from vehicle_agent.setup import VehicleSetup, vehicle_setup
from vehicle_agent.trace import JobTrace, TraceRecorder

SHOWS = Path(__file__).resolve().parent.parent / "shows"


def solo_job(tmp_path: Path, job_files: str) -> tuple[VehicleSetup, PreparedJob]:
    """uav1 of the solo show with its database in ``tmp_path`` and per-job files ``full`` or
    ``compact``, and its job "j1" (一) prepared."""
    show = load_show(SHOWS / "solo.yaml")
    storage = show.storage.model_copy(
        update={"database": tmp_path / "show.sqlite3", "job_files": job_files}
    )
    setup = vehicle_setup(show.model_copy(update={"storage": storage}), "uav1")
    return setup, prepare_job(setup, JobAssignment(job_id="j1", text="一"))


def _vec(row: np.ndarray) -> Vec3:
    return (float(row[0]), float(row[1]), float(row[2]))


def recorded_trace(
    job_id: str,
    attempt: int,
    t_s: np.ndarray,
    position_m_enu: np.ndarray,
    velocity_mps_enu: np.ndarray,
    reference_m_enu: np.ndarray,
    pen_down: np.ndarray,
    pen_contact: np.ndarray | None = None,
    pen_tip_m_enu: np.ndarray | None = None,
    pen_width_m: np.ndarray | None = None,
    force_n: np.ndarray | None = None,
) -> JobTrace:
    """The trace the agent records of a backend reporting these (N,) / (N, 3) arrays per tick
    (None: the backend does not know it)."""
    recorder = TraceRecorder()
    for i in range(t_s.shape[0]):
        snapshot = VehicleSnapshot(
            t_s=float(t_s[i]),
            position_m_enu=_vec(position_m_enu[i]),
            velocity_mps_enu=_vec(velocity_mps_enu[i]),
            armed=True,
            mode="offboard",
            on_ground=False,
            pen_contact=None if pen_contact is None else bool(pen_contact[i]),
            pen_tip_m_enu=None if pen_tip_m_enu is None else _vec(pen_tip_m_enu[i]),
            pen_width_m=None if pen_width_m is None else float(pen_width_m[i]),
            force_n=None if force_n is None else float(force_n[i]),
        )
        setpoint = Setpoint(_vec(reference_m_enu[i]), pen_down=bool(pen_down[i]))
        recorder.add(float(t_s[i]), snapshot, setpoint)
    return recorder.finish(job_id, attempt)

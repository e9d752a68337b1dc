"""What a vehicle actually flew while writing one job, sampled once per control period, in the
kinds' one trace format (:class:`vehicles.kind.FlownWriting`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from vehicle_agent.backends.base import Setpoint, VehicleSnapshot
from vehicles.kind import FlownWriting

FloatArray = NDArray[np.float64]

VELOCITY = "velocity_mps_enu"
"""``FlownWriting.extra`` entry: (K, 3) measured velocity in [m/s], ENU."""
PEN_CONTACT = "pen_contact"
"""``FlownWriting.extra`` entry, where the backend reports it: (K,) bool, the pen touched."""


@dataclass(frozen=True)
class JobTrace:
    """One job as flown by this vehicle: the kinds' trace and which assignment it was."""

    job_id: str
    """The job written."""
    attempt: int
    """Which assignment of the job this was (1 is the first)."""
    flown: FlownWriting
    """What was flown, one row per control tick: the reference the agent gave, the pen tip
    (``writing_point_m_enu``) and the vehicle reference point (``base_m_enu``), the ink laid,
    the measured force where sensed; ``extra`` holds :data:`VELOCITY` and, where the backend
    reports it, :data:`PEN_CONTACT`."""
    pen_known: bool
    """The backend reported its pen (tip, ink width and contact) at every tick. False (an
    autopilot without a brush model): ``flown.writing_point_m_enu`` is the vehicle reference
    point, ``base_m_enu`` None and ``ink_width_m`` zeros; nothing to score the ink by."""

    @property
    def duration_s(self) -> float:
        """Time in [s] from the first to the last sample."""
        t_s = self.flown.t_s
        return float(t_s[-1] - t_s[0]) if t_s.size else 0.0


class TraceRecorder:
    """Collects one sample per control period; :meth:`finish` turns them into a trace.

    ``add`` runs every tick of every vehicle of a fleet host: it only appends what the snapshot
    and the setpoint hold (plain tuples and numbers); the arrays are built once, in ``finish``.
    """

    def __init__(self) -> None:
        self._t: list[float] = []
        self._p: list[tuple[float, float, float]] = []
        self._v: list[tuple[float, float, float]] = []
        self._r: list[tuple[float, float, float]] = []
        self._pen: list[bool] = []
        self._contact: list[bool | None] = []
        self._tip: list[tuple[float, float, float] | None] = []
        self._width: list[float | None] = []
        self._force: list[float | None] = []

    def __len__(self) -> int:
        return len(self._t)

    def add(self, t_s: float, snapshot: VehicleSnapshot, setpoint: Setpoint) -> None:
        """Record the vehicle state at ``t_s`` and the reference it was given for that instant."""
        self._t.append(t_s)
        self._p.append(snapshot.position_m_enu)
        self._v.append(snapshot.velocity_mps_enu)
        self._r.append(setpoint.position_m_enu)
        self._pen.append(setpoint.pen_down)
        self._contact.append(snapshot.pen_contact)
        self._tip.append(snapshot.pen_tip_m_enu)
        self._width.append(snapshot.pen_width_m)
        self._force.append(snapshot.force_n)

    def finish(self, job_id: str, attempt: int, abort_reason: str | None = None) -> JobTrace:
        """The recorded samples as the job's :class:`JobTrace`; ``abort_reason``: why the job
        stopped before its end (``FlownWriting.abort_reason``), None: flown to its end."""
        contact_known = _known(self._contact)
        pen_known = contact_known and _known(self._tip) and _known(self._width)
        position = _vectors(self._p)
        extra: dict[str, NDArray[Any]] = {VELOCITY: _vectors(self._v)}
        if contact_known:
            extra[PEN_CONTACT] = np.asarray(self._contact, dtype=np.bool_)
        if pen_known:
            writing_point = _vectors(self._tip)
            width = np.asarray(self._width, dtype=np.float64)
            ink_width = np.where(extra[PEN_CONTACT], width, 0.0)
            base: FloatArray | None = position
        else:
            writing_point, ink_width, base = position, np.zeros(len(self._t)), None
        flown = FlownWriting(
            t_s=np.asarray(self._t, dtype=np.float64),
            reference_m_enu=_vectors(self._r),
            writing_point_m_enu=writing_point,
            pen_down=np.asarray(self._pen, dtype=np.bool_),
            ink_width_m=ink_width,
            base_m_enu=base,
            force_n=np.asarray(self._force, dtype=np.float64) if _known(self._force) else None,
            extra=extra,
            abort_reason=abort_reason,
        )
        return JobTrace(job_id, attempt, flown, pen_known)


def _known(values: Sequence[object]) -> bool:
    """Every sample is known (and there is one)."""
    return bool(values) and all(v is not None for v in values)


def _vectors(values: Sequence[object]) -> FloatArray:
    """(N, 3) float array of ``values``."""
    return np.asarray(values, dtype=np.float64).reshape(-1, 3)

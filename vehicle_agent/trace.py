"""What a vehicle actually flew while writing one job, sampled once per control period."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from vehicle_agent.backends.base import Setpoint, VehicleSnapshot

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


@dataclass(frozen=True)
class FlownTrace:
    """The flown and the reference trajectory of one job, aligned in time."""

    job_id: str
    """The job written."""
    attempt: int
    """Which assignment of the job this was (1 is the first)."""
    t_s: FloatArray
    """(N,) time in [s] since writing started."""
    position_m_enu: FloatArray
    """(N, 3) measured position in [m], ENU."""
    velocity_mps_enu: FloatArray
    """(N, 3) measured velocity in [m/s], ENU."""
    reference_m_enu: FloatArray
    """(N, 3) reference position in [m], ENU, at the same instants."""
    pen_down: BoolArray
    """(N,) True where the reference meant the brush to touch the board."""
    pen_contact: BoolArray | None
    """(N,) True where the backend saw the brush touch the board, when it knows."""
    pen_tip_m_enu: FloatArray | None = None
    """(N, 3) brush tip in [m], ENU, when the backend knows."""
    pen_width_m: FloatArray | None = None
    """(N,) painted stroke width in [m] (0 without contact), when the backend knows."""
    force_n: FloatArray | None = None
    """(N,) measured normal contact force in [N], for kinds that sense it."""

    @property
    def duration_s(self) -> float:
        """Time in [s] from the first to the last sample."""
        return float(self.t_s[-1] - self.t_s[0]) if self.t_s.size else 0.0


class TraceRecorder:
    """Collects one sample per control period; :meth:`finish` turns them into a trace."""

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

    def finish(self, job_id: str, attempt: int) -> FlownTrace:
        """The recorded samples as arrays."""
        known = bool(self._contact) and all(c is not None for c in self._contact)
        tips_known = bool(self._tip) and all(p is not None for p in self._tip)
        widths_known = bool(self._width) and all(w is not None for w in self._width)
        forces_known = bool(self._force) and all(f is not None for f in self._force)
        return FlownTrace(
            job_id=job_id,
            attempt=attempt,
            t_s=np.asarray(self._t, dtype=np.float64),
            position_m_enu=np.asarray(self._p, dtype=np.float64).reshape(-1, 3),
            velocity_mps_enu=np.asarray(self._v, dtype=np.float64).reshape(-1, 3),
            reference_m_enu=np.asarray(self._r, dtype=np.float64).reshape(-1, 3),
            pen_down=np.asarray(self._pen, dtype=np.bool_),
            pen_contact=np.asarray(self._contact, dtype=np.bool_) if known else None,
            pen_tip_m_enu=(
                np.asarray(self._tip, dtype=np.float64).reshape(-1, 3) if tips_known else None
            ),
            pen_width_m=np.asarray(self._width, dtype=np.float64) if widths_known else None,
            force_n=np.asarray(self._force, dtype=np.float64) if forces_known else None,
        )

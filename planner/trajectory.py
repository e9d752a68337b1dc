"""The planned trajectory of one character: spline, pen timeline, report, and ``TRAJ.json``."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from planner.board import BoardFrame
from planner.bspline import ClampedCubicSpline, FloatArray, IntArray
from planner.feasibility import FeasibilityReport
from planner.limits import VehicleLimits

if TYPE_CHECKING:
    from planner.samples import BoolArray, TrajectorySamples

TRAJ_FORMAT = "skyquill.traj/1"


@dataclass(frozen=True, eq=False)
class PlannedTrajectory:
    """A smooth rest-to-rest reference that writes one character, with its own report."""

    spline: ClampedCubicSpline
    """Position spline, world ENU in [m], t in [0, duration_s]."""
    feasibility: FeasibilityReport
    """Peaks against limits, thrust, body rate and fit error (see planner.feasibility)."""
    timing_ms: Mapping[str, float]
    """Wall time of each planning stage in [ms] (and ``"total"``)."""
    stroke_intervals_s: tuple[tuple[float, float], ...]
    """Per stroke: times of its approach point (above its start) and its lift point (above its
    end), [s]; the pen is down where the reference is at writing height within one of them."""
    write_z_m: float
    """World z of the reference while the brush writes, [m]."""
    pen_contact_tolerance_m: float
    """The pen counts as down within a stroke while ``z <= write_z_m + tolerance``, [m]."""
    turning_points_board_m: tuple[FloatArray, ...]
    """Per stroke: turning points in board-local [m], shape (k, 2)."""
    data_points_m_enu: FloatArray
    """All regression data points, world ENU [m], shape (N, 3)."""
    data_times_s: FloatArray
    """Their (re-segmented) times in [s], shape (N,)."""
    data_kinds: IntArray
    """``planner.waypoints.KIND_*`` of each data point, shape (N,)."""
    limits: VehicleLimits
    """Limits the trajectory was planned and checked against."""
    board: BoardFrame
    """Board the character is written on."""
    info: Mapping[str, Any]
    """Solver, method, costs before/after re-segmentation, iteration counts."""

    @property
    def duration_s(self) -> float:
        """Total time in [s]."""
        return self.spline.duration_s

    def evaluate(self, t_s: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Position [m], velocity [m/s], acceleration [m/s^2], jerk [m/s^3], each (n, 3) ENU."""
        t = np.asarray(t_s, dtype=np.float64).ravel()
        s = self.spline
        return s.evaluate(t, 0), s.evaluate(t, 1), s.evaluate(t, 2), s.evaluate(t, 3)

    def pen_down(self, t_s: FloatArray) -> BoolArray:
        """True where ``t`` lies in a stroke and the reference is at writing height."""
        t = np.asarray(t_s, dtype=np.float64).ravel()
        inside = np.zeros(t.shape, dtype=bool)
        for t0, t1 in self.stroke_intervals_s:
            inside |= (t >= t0) & (t <= t1)
        z = self.spline.evaluate(t)[:, 2]
        return np.asarray(inside & (z <= self.write_z_m + self.pen_contact_tolerance_m))

    def sample_times(self, rate_hz: float = 100.0) -> FloatArray:
        """``0, 1/rate, 2/rate, ...`` plus the end time if it is not on the grid."""
        n = int(np.floor(self.duration_s * rate_hz + 1e-9)) + 1
        t = np.arange(n) / rate_hz
        if self.duration_s - t[-1] > 1e-9:
            t = np.append(t, self.duration_s)
        return t

    def sample(self, rate_hz: float = 100.0) -> TrajectorySamples:
        """The reference at a fixed rate (the last sample is exactly at the end, at rest)."""
        from planner.samples import TrajectorySamples  # here: a plan only reported is not sampled

        t = self.sample_times(rate_hz)
        p, v, a, _ = self.evaluate(t)
        return TrajectorySamples(t, p, v, a, self.pen_down(t))

    def to_json_dict(self, rate_hz: float = 100.0) -> dict[str, Any]:
        """Content of ``TRAJ.json`` (see docs/formats.md)."""
        return {
            "format": TRAJ_FORMAT,
            "duration_s": round(self.duration_s, 6),
            "samples": self.sample(rate_hz).to_json_dict(),
            "sample_rate_hz": rate_hz,
            "limits": {
                "a_max": list(self.limits.a_max_mps2),
                "v_max": self.limits.v_max_mps,
                "mass_kg": self.limits.mass_kg,
                "thrust_max_n": self.limits.thrust_max_n,
                "body_rate_max_radps": self.limits.body_rate_max_radps,
            },
            "timing_ms": {k: round(v, 3) for k, v in self.timing_ms.items()},
            "feasibility": self.feasibility.to_json_dict(),
            "turning_points": [np.round(tp, 6).tolist() for tp in self.turning_points_board_m],
            "stroke_intervals_s": [list(iv) for iv in self.stroke_intervals_s],
            "board": asdict(self.board),
            "write_z_m": self.write_z_m,
            "spline": {
                "degree": 3,
                "n_spans": self.spline.n_spans,
                "duration_s": self.duration_s,
                "control_points": np.round(self.spline.control_points, 9).tolist(),
            },
            "info": dict(self.info),
        }

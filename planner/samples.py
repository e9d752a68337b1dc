"""Densely sampled reference trajectory: hand-over format between planner, controller, wire."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from planner.errors import PlannerError

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


@dataclass(frozen=True)
class TrajectorySamples:
    """A reference sampled at a fixed rate, world frame ENU, SI units.

    The controller reads it tick by tick; ``TRAJ.json`` stores it as ``samples``.
    """

    t_s: FloatArray
    """Sample times in [s], shape (N,), strictly increasing, starting at 0."""
    position_m_enu: FloatArray
    """Reference position in [m], shape (N, 3), world frame ENU."""
    velocity_mps_enu: FloatArray
    """Reference velocity in [m/s], shape (N, 3)."""
    acceleration_mps2_enu: FloatArray
    """Reference acceleration in [m/s^2], shape (N, 3)."""
    pen_down: BoolArray
    """True where the brush is meant to touch the board, shape (N,)."""

    def __post_init__(self) -> None:
        n = self.t_s.shape[0]
        for name in ("position_m_enu", "velocity_mps_enu", "acceleration_mps2_enu"):
            if getattr(self, name).shape != (n, 3):
                raise PlannerError(
                    f"shape {getattr(self, name).shape}, expected ({n}, 3)", field=name
                )
        if self.pen_down.shape != (n,):
            raise PlannerError(f"shape {self.pen_down.shape}, expected ({n},)", field="pen_down")
        if n < 2 or not bool(np.all(np.diff(self.t_s) > 0.0)):
            raise PlannerError("needs at least two strictly increasing times", field="t")

    @property
    def duration_s(self) -> float:
        """Time of the last sample in [s]."""
        return float(self.t_s[-1])

    @property
    def rate_hz(self) -> float:
        """Mean sample rate in [Hz]."""
        return float(int(self.t_s.shape[0]) - 1) / float(self.t_s[-1] - self.t_s[0])

    def index_at(self, t_s: float) -> int:
        """Index of the last sample at or before ``t_s`` (clamped to the ends)."""
        i = int(np.searchsorted(self.t_s, t_s, side="right")) - 1
        return min(max(i, 0), int(self.t_s.shape[0]) - 1)

    def stretched(self, factor: float) -> TrajectorySamples:
        """The same path flown ``factor`` times slower (``factor >= 1``), at the same rate:
        sample times ``t / factor`` of this reference, speeds divided by ``factor`` and
        accelerations by ``factor**2``. Positions and speeds between samples are cubic Hermite
        interpolants (exact on the planner's cubic spline within a span), accelerations
        linear; the pen is as at the sample at or before."""
        if not factor >= 1.0:
            raise PlannerError(f"must be >= 1, got {factor}", field="stretch")
        if factor == 1.0:
            return self
        n = round(self.duration_s * factor * self.rate_hz) + 1
        t_new = np.linspace(0.0, self.duration_s * factor, n)
        u = np.minimum(t_new / factor, self.t_s[-1])
        i = np.clip(np.searchsorted(self.t_s, u, side="right") - 1, 0, self.t_s.shape[0] - 2)
        return TrajectorySamples(
            t_new,
            _hermite(self.t_s, self.position_m_enu, self.velocity_mps_enu, i, u),
            _hermite(self.t_s, self.velocity_mps_enu, self.acceleration_mps2_enu, i, u) / factor,
            np.column_stack(
                [np.interp(u, self.t_s, self.acceleration_mps2_enu[:, k]) for k in range(3)]
            )
            / factor**2,
            self.pen_down[np.clip(np.searchsorted(self.t_s, u, side="right") - 1, 0, None)],
        )

    def to_json_dict(self) -> dict[str, Any]:
        """The ``samples`` object of ``TRAJ.json`` (see docs/formats.md)."""
        return {
            "t": np.round(self.t_s, 6).tolist(),
            "p": np.round(self.position_m_enu, 6).tolist(),
            "v": np.round(self.velocity_mps_enu, 6).tolist(),
            "a": np.round(self.acceleration_mps2_enu, 6).tolist(),
            "pen_down": self.pen_down.tolist(),
        }

    @classmethod
    def from_json_dict(cls, data: dict[str, Any]) -> TrajectorySamples:
        """Inverse of :meth:`to_json_dict`; raises :class:`PlannerError` naming a bad field."""
        try:
            t = np.asarray(data["t"], dtype=np.float64)
            p = np.asarray(data["p"], dtype=np.float64).reshape(-1, 3)
            v = np.asarray(data["v"], dtype=np.float64).reshape(-1, 3)
            a = np.asarray(data["a"], dtype=np.float64).reshape(-1, 3)
            pen = np.asarray(data["pen_down"], dtype=np.bool_)
        except KeyError as exc:
            raise PlannerError("missing", field=f"samples.{exc.args[0]}") from None
        except (TypeError, ValueError) as exc:
            raise PlannerError(f"not a numeric array: {exc}", field="samples") from None
        return cls(t, p, v, a, pen)


def _hermite(
    t_s: FloatArray, value: FloatArray, slope: FloatArray, i: NDArray[np.intp], u: FloatArray
) -> FloatArray:
    """Cubic Hermite interpolation of ``value`` (N, 3) with time derivative ``slope`` at times
    ``u`` lying in the intervals ``[t_s[i], t_s[i + 1]]``."""
    h = (t_s[i + 1] - t_s[i])[:, None]
    s = ((u - t_s[i]) / (t_s[i + 1] - t_s[i]))[:, None]
    h00 = 2 * s**3 - 3 * s**2 + 1
    h10 = s**3 - 2 * s**2 + s
    h01 = -2 * s**3 + 3 * s**2
    h11 = s**3 - s**2
    out: FloatArray = (
        h00 * value[i] + h10 * h * slope[i] + h01 * value[i + 1] + h11 * h * slope[i + 1]
    )
    return out

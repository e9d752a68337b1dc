"""A job's reference sampled at each control tick: the plan's samples interpolated at agent time.

Read through ``memoryview`` s of the plan's own arrays (no copy): a tick reads two rows of three
columns as Python floats and finds its sample by bisection, about 3 us, where the same through
numpy (``searchsorted``, row indexing, ``tolist``) took about 12 us, at every tick of every
vehicle in flight (about a tenth of a fleet host's time with 25 vehicles writing).
"""

from __future__ import annotations

from bisect import bisect_right

import numpy as np
from numpy.typing import NDArray

from planner.samples import TrajectorySamples
from vehicle_agent.backends.base import Setpoint, Vec3


class ReferenceTrack:
    """``samples`` (and the wanted contact force per sample, in [N], when given) at any time."""

    def __init__(
        self, samples: TrajectorySamples, force_n: NDArray[np.float64] | None = None
    ) -> None:
        self._t_s = _floats(samples.t_s)
        self._last = len(self._t_s) - 1
        self._position = _floats(samples.position_m_enu)
        self._velocity = _floats(samples.velocity_mps_enu)
        self._acceleration = _floats(samples.acceleration_mps2_enu)
        self._pen_down = np.ascontiguousarray(samples.pen_down, dtype=np.bool_).data
        self._force_n = None if force_n is None else _floats(force_n)

    def at(self, t_s: float) -> Setpoint:
        """The reference at ``t_s`` in [s] from the plan's start, linearly interpolated between
        samples (clamped at both ends); the pen is the nearer sample's."""
        i, j, w = self._bracket(t_s)
        position, velocity, acceleration = self._motion(i, j, w)
        force = self._force_n
        return Setpoint(
            position_m_enu=position,
            velocity_mps_enu=velocity,
            acceleration_mps2_enu=acceleration,
            pen_down=bool(self._pen_down[i] if w < 0.5 else self._pen_down[j]),
            force_n=None if force is None else (1.0 - w) * force[i] + w * force[j],
        )

    def motion_at(self, t_s: float) -> tuple[Vec3, Vec3, Vec3]:
        """Position in [m], velocity in [m/s] and acceleration in [m/s^2] at ``t_s`` (as
        :meth:`at`, without the pen)."""
        return self._motion(*self._bracket(t_s))

    def _bracket(self, t_s: float) -> tuple[int, int, float]:
        """The samples around ``t_s`` and the weight of the later one."""
        times, last = self._t_s, self._last
        i = min(max(bisect_right(times, t_s) - 1, 0), last)
        j = min(i + 1, last)
        t_i = times[i]
        span = times[j] - t_i
        return i, j, 0.0 if span <= 0.0 else min(max((t_s - t_i) / span, 0.0), 1.0)

    def _motion(self, i: int, j: int, w: float) -> tuple[Vec3, Vec3, Vec3]:
        keep, a, b = 1.0 - w, 3 * i, 3 * j

        def lerp(flat: memoryview) -> Vec3:
            return (
                keep * flat[a] + w * flat[b],
                keep * flat[a + 1] + w * flat[b + 1],
                keep * flat[a + 2] + w * flat[b + 2],
            )

        return lerp(self._position), lerp(self._velocity), lerp(self._acceleration)


def _floats(values: NDArray[np.float64]) -> memoryview:
    """A flat read-only view of ``values`` as float64 (copied only if not so already)."""
    flat = np.ascontiguousarray(values, dtype=np.float64).reshape(-1)
    return flat.data.toreadonly()

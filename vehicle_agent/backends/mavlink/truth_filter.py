"""The simulator's truth without its centimetre steps (pure).

ArduPilot SITL sends SIM_STATE positions as ``lat_int``/``lon_int`` in 1e-7 degrees and ``alt``
in whole centimetres, PX4 SIH's HIL_STATE_QUATERNION lat/lon the same way: the truth moves in
steps of 0.9-1.1 cm (measured on ArduCopter SITL: x holds still for 1.2 s, then jumps 9 mm). As
the mocap forwarded to the autopilot and as the yardstick of a job's writing, that staircase is
a centimetre of error by itself. Both messages carry the velocity unquantized (SIM_STATE in m/s,
HIL_STATE_QUATERNION in cm/s), so :class:`SmoothedTruthTracker` carries the position forward on
the velocity between samples and pulls it towards each quantized sample with time constant
``time_constant_s``: the steps average out, the motion stays.
"""

from __future__ import annotations

from typing import Any

from vehicle_agent.backends.mavlink.frames import Vec3
from vehicle_agent.backends.mavlink.truth import TruthSample, TruthTracker

SNAP_M = 0.03
"""A quantized sample further than this in [m] from the smoothed one restarts the smoothing
(a reset of the simulator, a jump the velocity did not announce)."""


def truth_velocity_mps_enu(message: Any) -> Vec3 | None:
    """The true velocity in [m/s], ENU, of a SIM_STATE or HIL_STATE_QUATERNION; else None."""
    kind = message.get_type()
    if kind == "SIM_STATE":
        north, east, down = float(message.vn), float(message.ve), float(message.vd)
    elif kind == "HIL_STATE_QUATERNION":
        north, east, down = message.vx / 100.0, message.vy / 100.0, message.vz / 100.0
    else:
        return None
    return (east, north, -down)


class SmoothedTruthTracker(TruthTracker):
    """A :class:`TruthTracker` whose samples are the velocity-aided smoothing of the quantized
    positions (attitudes and times as they came)."""

    def __init__(
        self, home_m_enu: Vec3, history_s: float = 1.0, time_constant_s: float = 0.4
    ) -> None:
        super().__init__(home_m_enu, history_s)
        self.time_constant_s = time_constant_s
        """Time in [s] over which the smoothed position is pulled to the quantized one."""
        self._last: TruthSample | None = None
        self._velocity: Vec3 = (0.0, 0.0, 0.0)

    def absorb(self, message: Any, now_s: float, *, resting_at_home: bool) -> bool:
        if not super().absorb(message, now_s, resting_at_home=resting_at_home):
            return False
        raw = self.samples[-1]
        velocity = truth_velocity_mps_enu(message) or (0.0, 0.0, 0.0)
        smoothed = self._smooth(raw, velocity)
        self.samples[-1] = smoothed
        self._last, self._velocity = smoothed, velocity
        return True

    def _smooth(self, raw: TruthSample, velocity: Vec3) -> TruthSample:
        last = self._last
        if last is None:
            return raw
        dt = max(0.0, raw.time_s - last.time_s)
        mean_v = [(velocity[i] + self._velocity[i]) / 2.0 for i in range(3)]
        predicted = [last.position_m_enu[i] + mean_v[i] * dt for i in range(3)]
        gap = [raw.position_m_enu[i] - predicted[i] for i in range(3)]
        if max(abs(g) for g in gap) > SNAP_M:
            return raw
        gain = min(1.0, dt / self.time_constant_s)
        p = (predicted[0] + gain * gap[0], predicted[1] + gain * gap[1],
             predicted[2] + gain * gap[2])  # fmt: skip
        return TruthSample(raw.time_s, p, raw.attitude_ned_rad)

"""The simulator's truth without its centimetre steps (pure).

ArduPilot SITL sends SIM_STATE positions as ``lat_int``/``lon_int`` in 1e-7 degrees and ``alt``
in whole centimetres, PX4 SIH's HIL_STATE_QUATERNION lat/lon the same way: the truth moves in
steps of 0.9-1.1 cm (measured on ArduCopter SITL: x holds still for 1.2 s, then jumps 9 mm). As
the mocap forwarded to the autopilot and as the yardstick of a job's writing, that staircase is
a centimetre of error by itself. Both messages carry the velocity (SIM_STATE in m/s, as floats;
HIL_STATE_QUATERNION in whole cm/s), so :class:`SmoothedTruthTracker` carries the position
forward on the velocity between samples, over the simulator's own clock, and pulls it towards
each quantized sample with a time constant set by how good that velocity is
(:data:`TIME_CONSTANT_S`): the steps average out, the motion stays.
"""

from __future__ import annotations

from typing import Any

from vehicle_agent.backends.mavlink.frames import Vec3
from vehicle_agent.backends.mavlink.truth import TruthSample, TruthTracker

TIME_CONSTANT_S = {"SIM_STATE": 2.0, "HIL_STATE_QUATERNION": 0.4}
"""How long in [s] the smoothed position takes to come to each quantized one, per message.
SIM_STATE's velocity is unquantized, so a long pull only averages more steps out. Fed back as
the mocap, the steps are a quantizer in the position loop: at 0.4 s ArduCopter SITL circled
them, +-1-2 cm at 0.3-0.5 Hz on a straight stroke, two `not_settled` in four jobs (issue 31,
two vehicles, load 1: pen-down RMSE median 8.9 mm, IoU 0.59); at 2.0 s 5.3 mm, IoU 0.68, all
settled. HIL_STATE_QUATERNION's velocity is in whole cm/s: the pull must stay short,
since a velocity off by up to 5 mm/s leaves the position that times the time constant behind."""
CLOCK_SLACK_S = 0.1
"""How far in [s] the simulator's clock may run ahead of the arrivals between two samples."""
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


def simulator_time_s(autopilot_time_ms: int) -> float | None:
    """When in [s] on the simulator's clock a truth message was sent: neither carries it
    (SIM_STATE has no stamp, PX4 leaves HIL_STATE_QUATERNION's ``time_usec`` 0), but each goes
    out beside the ATTITUDE asked for at its rate, whose ``time_boot_ms`` (``autopilot_time_ms``,
    0: none yet) stands for it."""
    return autopilot_time_ms * 1e-3 if autopilot_time_ms > 0 else None


def elapsed_s(clock_dt_s: float | None, arrival_dt_s: float) -> float:
    """The time in [s] to carry the position over: the simulator's (``clock_dt_s``), unless it
    stood still or ran ahead of the arrivals by more than :data:`CLOCK_SLACK_S` (an ATTITUDE
    lost or late), then the arrivals'."""
    if clock_dt_s is None or not 0.0 < clock_dt_s <= arrival_dt_s + CLOCK_SLACK_S:
        return max(0.0, arrival_dt_s)
    return clock_dt_s


class SmoothedTruthTracker(TruthTracker):
    """A :class:`TruthTracker` whose samples are the velocity-aided smoothing of the quantized
    positions (attitudes and times as they came)."""

    def __init__(self, home_m_enu: Vec3, history_s: float = 1.0) -> None:
        super().__init__(home_m_enu, history_s)
        self._last: TruthSample | None = None
        self._last_clock_s: float | None = None
        """The simulator's clock at the last sample (None: not known)."""
        self._velocity: Vec3 = (0.0, 0.0, 0.0)

    def absorb(
        self,
        message: Any,
        now_s: float,
        *,
        resting_at_home: bool,
        simulator_s: float | None = None,
    ) -> bool:
        """As :meth:`TruthTracker.absorb`; ``simulator_s``: when in [s] on the simulator's clock
        the message was sent (:func:`simulator_time_s`; None: not known). A loaded simulator's
        clock runs slower than the agent's, and the velocity moves the position by the
        simulator's seconds."""
        if not super().absorb(message, now_s, resting_at_home=resting_at_home):
            return False
        raw = self.samples[-1]
        velocity = truth_velocity_mps_enu(message) or (0.0, 0.0, 0.0)
        smoothed = self._smooth(raw, velocity, simulator_s, TIME_CONSTANT_S[message.get_type()])
        self.samples[-1] = smoothed
        self._last, self._velocity, self._last_clock_s = smoothed, velocity, simulator_s
        return True

    def _smooth(
        self, raw: TruthSample, velocity: Vec3, clock_s: float | None, time_constant_s: float
    ) -> TruthSample:
        last = self._last
        if last is None:
            return raw
        clock_dt = None if clock_s is None or self._last_clock_s is None else (
            clock_s - self._last_clock_s)  # fmt: skip
        dt = elapsed_s(clock_dt, raw.time_s - last.time_s)
        mean_v = [(velocity[i] + self._velocity[i]) / 2.0 for i in range(3)]
        predicted = [last.position_m_enu[i] + mean_v[i] * dt for i in range(3)]
        gap = [raw.position_m_enu[i] - predicted[i] for i in range(3)]
        if max(abs(g) for g in gap) > SNAP_M:
            return raw
        gain = min(1.0, dt / time_constant_s)
        p = (predicted[0] + gain * gap[0], predicted[1] + gain * gap[1],
             predicted[2] + gain * gap[2])  # fmt: skip
        return TruthSample(raw.time_s, p, raw.attitude_ned_rad)

"""The simulator's truth without its centimetre steps (pure).

ArduPilot SITL sends SIM_STATE positions as ``lat_int``/``lon_int`` in 1e-7 degrees and ``alt``
in whole centimetres, PX4 SIH's HIL_STATE_QUATERNION lat/lon the same way: the truth moves in
steps of 0.9-1.1 cm (measured on ArduCopter SITL: x holds still for 1.2 s, then jumps 9 mm). As
the mocap forwarded to the autopilot and as the yardstick of a job's writing, that staircase is
a centimetre of error by itself. Both messages carry the velocity (SIM_STATE in m/s, as floats;
HIL_STATE_QUATERNION in whole cm/s, truncated: :func:`mid_step_mps`), so
:class:`SmoothedTruthTracker` carries the position forward on the velocity between samples, over
the simulator's own clock, and pulls it towards each quantized sample with a time constant set
by how good that velocity is (:data:`TIME_CONSTANT_S`): the steps average out, the motion stays.
Neither message says when its sample was taken, except HIL_STATE_QUATERNION from a PX4 built by
scripts/sitl/build.py (:func:`own_time_s`): its samples are carried over and stamped on that
time (:class:`CaptureClock`), the others on the last ATTITUDE's and on their arrival. Such a PX4
also sends the same truth as floats (:data:`~vehicle_agent.backends.mavlink.truth.EXACT_TRUTH`),
whose positions have no steps to smooth: the smoothing is for ArduPilot and PX4 as shipped.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Any

from vehicle_agent.backends.mavlink.frames import Vec3
from vehicle_agent.backends.mavlink.truth import EXACT_TRUTH, TruthSample, TruthTracker

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
CAPTURE_WINDOW_S = 2.0
"""Over how much of the simulator's clock in [s] the least delay of a stamped truth (its arrival
minus its own time) is taken."""
CAPTURE_OFFSET_TIME_CONSTANT_S = 1.0
"""How slowly in [s] the agent's estimate of that delay follows it: the samples keep the
simulator's spacing, not the link's jitter."""
CAPTURE_OFFSET_RESET_S = 0.5
"""A least delay this much longer in [s] than the estimate (a stalled link, a restarted
simulator) is taken at once."""


def truth_velocity_mps_enu(message: Any) -> Vec3 | None:
    """The true velocity in [m/s], ENU, of a SIM_STATE or HIL_STATE_QUATERNION; else None."""
    kind = message.get_type()
    if kind == "SIM_STATE":
        north, east, down = float(message.vn), float(message.ve), float(message.vd)
    elif kind == "HIL_STATE_QUATERNION":
        north, east, down = (mid_step_mps(message.vx), mid_step_mps(message.vy),
                             mid_step_mps(message.vz))  # fmt: skip
    else:
        return None
    return (east, north, -down)


def mid_step_mps(whole_cm_s: int) -> float:
    """The velocity in [m/s] at the middle of the step PX4 sends as ``whole_cm_s`` [cm/s]:
    HIL_STATE_QUATERNION's velocity is ``lpos.vx * 1e2f`` stored in an int16 (PX4 v1.16,
    ``src/modules/mavlink/streams/HIL_STATE_QUATERNION.hpp``), which truncates towards zero, so
    3 stands for [3, 4) cm/s, -3 for (-4, -3] and 0 for (-1, 1). Read as whole cm/s, a writing
    stroke's velocity was 0.5 cm/s short on average and the smoothed truth trailed the vehicle
    by that times :data:`TIME_CONSTANT_S`. Replayed on PX4 SIH's exact truth (four ULogs of the
    50-job show, issue 31): the smoothed truth's error at 1-30 cm/s 2.07 -> 1.07 mm RMS per axis
    (mean over speed bands and logs)."""
    return 0.0 if whole_cm_s == 0 else (whole_cm_s + math.copysign(0.5, whole_cm_s)) / 100.0


def own_time_s(message: Any) -> float | None:
    """When in [s] on the simulator's clock a truth sample was taken, where the message says so:
    HIL_STATE_QUATERNION's (and :data:`~vehicle_agent.backends.mavlink.truth.EXACT_TRUTH`'s)
    ``time_usec`` from a PX4 built with scripts/sitl/source_edits.py (PX4 as shipped, and
    SIM_STATE, carry no time: None)."""
    if message.get_type() not in ("HIL_STATE_QUATERNION", EXACT_TRUTH):
        return None
    time_us = int(message.time_usec)
    return time_us * 1e-6 if time_us > 0 else None


def simulator_time_s(autopilot_time_ms: int) -> float | None:
    """When in [s] on the simulator's clock a truth message was sent, for a message that does not
    say when its sample was taken (SIM_STATE; HIL_STATE_QUATERNION from PX4 as shipped, which
    leaves ``time_usec`` 0: else :func:`own_time_s`, which the tracker prefers): each goes out
    beside the ATTITUDE asked for at its rate, whose ``time_boot_ms`` (``autopilot_time_ms``, 0:
    none yet) stands for it."""
    return autopilot_time_ms * 1e-3 if autopilot_time_ms > 0 else None


@dataclass(frozen=True)
class SimulatorClock:
    """Where the smoothed truth stands on the simulator's clock."""

    seen_s: float
    """The simulator's clock at the last sample, in [s]."""
    at_s: float
    """The simulator time in [s] the smoothed position stands for: the clock, or beyond it by
    the arrivals carried over while the clock stood still."""


def carry_s(
    clock: SimulatorClock | None, clock_s: float | None, arrival_dt_s: float
) -> tuple[float, SimulatorClock | None]:
    """The time in [s] to carry the position over to a sample that arrived ``arrival_dt_s``
    [s] after the last and was sent at ``clock_s`` on the simulator's clock (None: unknown), and
    the clock after it. The simulator's time since the position's, unless the clock stood still
    (an ATTITUDE slower than the truth, or none: PX4 leaves HIL_STATE_QUATERNION's time_usec 0),
    then the arrivals', which the clock's next step then pays back; never more than the
    arrivals' by :data:`CLOCK_SLACK_S` (an ATTITUDE lost or late). Taking both in full counted
    the time twice whenever no ATTITUDE came between two truth samples. Measured on PX4 SIH
    (issue 31, its ULogs): in one vehicle's flights the mocap made of the smoothed truth ran
    0.4-0.7 cm ahead of the simulator's along transits, up to 3 cm, snapped back, and its
    velocity jumped to -1 m/s (13-25 times a flight); EKF2 rejected the velocity (test ratio
    12-14), dropped the vision height for 0.1 s, and the vehicle left its transit by 0.15-0.21 m
    seven times: its jobs handed back, one given up after three tries. The other vehicle's mocap
    trailed by the mocap latency."""
    arrival_s = max(0.0, arrival_dt_s)
    if clock_s is None:
        return arrival_s, clock
    if clock is None:
        return arrival_s, SimulatorClock(clock_s, clock_s)
    if clock_s <= clock.seen_s:
        return arrival_s, SimulatorClock(clock.seen_s, clock.at_s + arrival_s)
    dt = min(max(0.0, clock_s - clock.at_s), arrival_s + CLOCK_SLACK_S)
    return dt, SimulatorClock(clock_s, max(clock_s, clock.at_s + dt))


class CaptureClock:
    """When a truth sample stamped with its own time was taken, on the agent's clock: its own
    time plus the link's least delay over the last :data:`CAPTURE_WINDOW_S` of the simulator's
    clock, taken at once when it falls and low-passed over :data:`CAPTURE_OFFSET_TIME_CONSTANT_S`
    of it when it rises. Stamped on arrival, samples taken 20 ms apart can come 1 ms apart
    (:class:`~vehicle_agent.backends.mavlink.odometry.PoseVelocity`), and the mocap's velocity,
    differenced over the stamps, is off by as much as their spacing is. PX4 SIH, research
    airframe, 12 held-out jobs (issue 31, docs/sitl.md; three runs, one at load 4): EKF2's
    velocity error while writing at 0.2-1 Hz 4.9 -> 3.3-3.4 mm/s, pen-down RMSE median
    6.6-6.8 -> 6.0-6.2 mm, IoU median 0.70 -> 0.72-0.74. The least delay, not the mean: a
    backlog read at once (the agent starting while the autopilot already streams) comes late
    all together, and a sample stamped after it arrived is not yet the mocap's."""

    def __init__(self) -> None:
        self._delays: deque[tuple[float, float]] = deque()
        """(own time [s], delay [s]) of the window's samples that no later one undercuts: the
        delays rise from the first, which is the least."""
        self._offset_s: float | None = None
        self._own_s = 0.0

    def capture_s(self, own_s: float, arrival_s: float) -> float:
        """The agent time in [s] of a sample taken at ``own_s`` [s] (simulator's clock) that
        arrived at ``arrival_s`` [s] (agent's clock)."""
        delays, delay_s = self._delays, arrival_s - own_s
        if delays and own_s < delays[-1][0]:
            delays.clear()  # the simulator restarted
        while delays and delays[-1][1] >= delay_s:
            delays.pop()  # never the least again while this one is in the window
        delays.append((own_s, delay_s))
        while own_s - delays[0][0] > CAPTURE_WINDOW_S:
            delays.popleft()
        least_s = delays[0][1]
        offset_s = self._offset_s
        if offset_s is None or not offset_s <= least_s <= offset_s + CAPTURE_OFFSET_RESET_S:
            self._offset_s = least_s  # the first; a faster link (none stamped after it came)
        else:
            gain = min(1.0, max(0.0, own_s - self._own_s) / CAPTURE_OFFSET_TIME_CONSTANT_S)
            self._offset_s = offset_s + gain * (least_s - offset_s)
        self._own_s = own_s
        return own_s + self._offset_s


class SmoothedTruthTracker(TruthTracker):
    """A :class:`TruthTracker` whose samples are the velocity-aided smoothing of the quantized
    positions (attitudes as they came; times as they came, or when taken where the message
    carries its own: :class:`CaptureClock`); :data:`~vehicle_agent.backends.mavlink.truth.
    EXACT_TRUTH`'s positions, which have no steps, as they came."""

    def __init__(self, home_m_enu: Vec3, history_s: float = 1.0) -> None:
        super().__init__(home_m_enu, history_s)
        self._last: TruthSample | None = None
        self._clock: SimulatorClock | None = None
        """Where the smoothed position stands on the simulator's clock (None: not known)."""
        self._velocity: Vec3 = (0.0, 0.0, 0.0)
        self._capture = CaptureClock()

    def absorb(
        self,
        message: Any,
        now_s: float,
        *,
        resting_at_home: bool,
        simulator_s: float | None = None,
    ) -> bool:
        """As :meth:`TruthTracker.absorb`; ``simulator_s``: when in [s] on the simulator's clock
        the message was sent (:func:`simulator_time_s`; None: not known), unless the message
        says when its sample was taken (:func:`own_time_s`). A loaded simulator's clock runs
        slower than the agent's, and the velocity moves the position by the simulator's
        seconds."""
        own_s = own_time_s(message)
        if own_s is not None:
            simulator_s = own_s
            now_s = self._capture.capture_s(own_s, now_s)
        if not super().absorb(message, now_s, resting_at_home=resting_at_home):
            return False
        if message.get_type() == EXACT_TRUTH:
            return True  # no steps to smooth (and the quantized ones no longer come here)
        raw = self.samples[-1]
        velocity = truth_velocity_mps_enu(message) or (0.0, 0.0, 0.0)
        smoothed = self._smooth(raw, velocity, simulator_s, TIME_CONSTANT_S[message.get_type()])
        self.samples[-1] = smoothed
        self._last, self._velocity = smoothed, velocity
        return True

    def _smooth(
        self, raw: TruthSample, velocity: Vec3, clock_s: float | None, time_constant_s: float
    ) -> TruthSample:
        last = self._last
        arrival_dt = 0.0 if last is None else raw.time_s - last.time_s
        dt, self._clock = carry_s(self._clock, clock_s, arrival_dt)
        if last is None:
            return raw
        mean_v = [(velocity[i] + self._velocity[i]) / 2.0 for i in range(3)]
        predicted = [last.position_m_enu[i] + mean_v[i] * dt for i in range(3)]
        gap = [raw.position_m_enu[i] - predicted[i] for i in range(3)]
        if max(abs(g) for g in gap) > SNAP_M:
            return raw
        gain = min(1.0, dt / time_constant_s)
        p = (predicted[0] + gain * gap[0], predicted[1] + gain * gap[1],
             predicted[2] + gain * gap[2])  # fmt: skip
        return TruthSample(raw.time_s, p, raw.attitude_ned_rad)

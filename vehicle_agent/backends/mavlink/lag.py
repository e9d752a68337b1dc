"""The autopilot's position response, identified in flight and compensated (pure).

An autopilot's position loop (ArduCopter's, PX4's) follows a p, v, a setpoint stream with a lag:
on ArduCopter SITL the vehicle sits 0.10-0.13 s behind the target along the path, at a gain of
about one. :class:`ResponseDelayEstimator` measures that delay from the flight itself (any leg
where the setpoint moves: the transit to the first stroke comes before the brush goes down): it
keeps the last seconds of setpoints sent and positions read back (the body's in the air, the
brush tip's on the board: ``ResponseAid.measured``) and finds the delay ``d`` that
best explains ``measured(t) = sent(t - d)`` (no free offset: along a straight leg a delay and an
offset would be the same thing) in the horizontal plane, where the brush writes on a board: the
vertical loop (thrust) answers a climb or a descent not as a delay (on ArduCopter SITL its climb
errors of 2-3 cm left no 3-D fit of a take-off, transit and two characters plausible, 0 of 59,
while the horizontal fits gave 0.055-0.07 s). :func:`lead_setpoint` then streams the
setpoint that lies ``d`` ahead on the plan, extrapolated along its velocity and acceleration, so
the vehicle is where the plan is when the plan is there.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from vehicle_agent.backends.base import Setpoint, Vec3

JERK_MAX_DT_S = 0.05
"""Longest gap in [s] between two setpoints whose accelerations give the plan's jerk."""
JERK_MAX_MPS3 = 20.0
"""Largest jerk in [m/s^3] taken from two setpoints (a plan's is a few; a jump is no jerk)."""


@dataclass(frozen=True)
class LagSettings:
    """How the response delay is identified and compensated."""

    window_s: float = 3.0
    """Length in [s] of the history a delay is fitted on."""
    min_path_m: float = 0.15
    """Least horizontal setpoint travel in [m] inside the window for a fit (a hover or a climb
    says nothing)."""
    max_delay_s: float = 0.4
    """Largest delay in [s] considered (and so the largest lead ever applied)."""
    step_s: float = 0.005
    """Grid step in [s] of the delay search."""
    refit_every_s: float = 0.5
    """Time in [s] between fits while the setpoint moves."""
    smoothing: float = 0.5
    """Weight of a new fit in the running delay (1: take each fit as it is)."""
    explained_fraction: float = 0.5
    """A fit identifies the delay only when it leaves at most this fraction of the zero-delay RMS
    error (a leg the delay clearly explains)."""
    refine_fraction: float = 0.8
    """Once a delay is identified, a fit leaving at most this fraction refines it. On PX4 1.16
    SIH the vehicle wanders 6-8 mm about its setpoint, as much as a 0.05 s delay at writing speed
    (0.2 m/s: 10 mm), so only fast transits explained half their error; with its gains at 2.5x
    their fits (0.08-0.09 s) alone led the writing 0.03-0.04 s too far (一 16.9 mm, IoU 0.50);
    refined by the writing legs the lead settled at 0.03-0.06 s (11.2 mm, 0.65). Not for
    identifying: on mavsim's stiff PX4 loop (no delay) one fit of a transient explained a third
    (0.113 s) and, taken, over-led a show's strokes to 20 mm."""


@dataclass(frozen=True)
class DelayFit:
    """One fit of the delay."""

    delay_s: float
    """Delay in [s] of the measured position behind the setpoint."""
    rms_m: float
    """RMS in [m] of what the delay does not explain."""
    rms_at_zero_m: float
    """The same RMS in [m] with no delay, for comparison."""


def fit_delay(
    t_sent_s: np.ndarray,
    sent_m: np.ndarray,
    t_measured_s: np.ndarray,
    measured_m: np.ndarray,
    settings: LagSettings,
) -> DelayFit | None:
    """The delay of ``measured`` (K, 3) behind ``sent`` (N, 3), both positions in [m] ENU in one
    frame at times in [s], fitted on east and north; None when the setpoint did not move far
    enough horizontally to tell."""
    if t_sent_s.size < 3 or t_measured_s.size < 3:
        return None
    sent_m, measured_m = sent_m[:, :2], measured_m[:, :2]
    travel = float(np.sum(np.linalg.norm(np.diff(sent_m, axis=0), axis=1)))
    if travel < settings.min_path_m:
        return None
    usable = t_measured_s - settings.max_delay_s >= t_sent_s[0]
    if np.count_nonzero(usable) < 3:
        return None
    t, measured = t_measured_s[usable], measured_m[usable]
    delays = np.arange(0.0, settings.max_delay_s + 1e-9, settings.step_s)
    costs = np.array([_residual_rms(t_sent_s, sent_m, t - d, measured) for d in delays])
    best = int(np.argmin(costs))
    delay = float(delays[best])
    if 0 < best < delays.size - 1:  # parabola through the three best points
        c0, c1, c2 = costs[best - 1], costs[best], costs[best + 1]
        curvature = c0 - 2 * c1 + c2
        if curvature > 0:
            delay += 0.5 * settings.step_s * float(c0 - c2) / float(curvature)
    return DelayFit(delay, float(costs[best]), float(costs[0]))


def _residual_rms(
    t_sent: np.ndarray, sent: np.ndarray, t: np.ndarray, measured: np.ndarray
) -> float:
    shifted = np.column_stack([np.interp(t, t_sent, sent[:, k]) for k in range(sent.shape[1])])
    residual = measured - shifted
    return float(np.sqrt(np.mean(np.sum(residual**2, axis=1))))


class ResponseDelayEstimator:
    """Keeps the recent setpoints and positions of one vehicle and refits its delay."""

    def __init__(self, settings: LagSettings | None = None) -> None:
        self.settings = settings or LagSettings()
        self.delay_s: float | None = None
        """The running delay in [s]; None until a leg of motion has been seen."""
        self.fits: list[DelayFit] = []
        """Every fit so far, oldest first."""
        self._sent: deque[tuple[float, Vec3]] = deque()
        self._measured: deque[tuple[float, Vec3]] = deque()
        self._last_fit_s = -np.inf

    def reset(self) -> None:
        """A new flight: forget the history (the delay identified so far stays)."""
        self._sent.clear()
        self._measured.clear()

    def sent(self, t_s: float, position_m: Vec3) -> None:
        """A setpoint position in [m] went out at agent time ``t_s`` [s]."""
        self._sent.append((t_s, position_m))
        self._trim(t_s)

    def measured(self, t_s: float, position_m: Vec3) -> None:
        """The vehicle's position in [m] (same frame) read at agent time ``t_s`` [s]; refits the
        delay when due."""
        self._measured.append((t_s, position_m))
        self._trim(t_s)
        if t_s - self._last_fit_s >= self.settings.refit_every_s:
            self._refit(t_s)

    def plausible(self, fit: DelayFit) -> bool:
        """A delay explains the response: inside the search range (not at its end) and leaving at
        most ``explained_fraction`` of the error at zero delay, or ``refine_fraction`` once a
        delay has been identified; otherwise the vehicle is not following the setpoints as a
        delay (it is disturbed, saturated or elsewhere) and the lead stays as it is."""
        inside = fit.delay_s < self.settings.max_delay_s - self.settings.step_s
        fraction = self.settings.explained_fraction
        if self.delay_s is not None:
            fraction = self.settings.refine_fraction
        return inside and fit.rms_m <= fraction * fit.rms_at_zero_m

    def _trim(self, now_s: float) -> None:
        horizon = now_s - self.settings.window_s - self.settings.max_delay_s
        for history in (self._sent, self._measured):
            while history and history[0][0] < horizon:
                history.popleft()

    def _refit(self, now_s: float) -> None:
        if len(self._sent) < 3 or len(self._measured) < 3:
            return
        t_sent = np.array([t for t, _ in self._sent])
        sent = np.array([p for _, p in self._sent])
        t_meas = np.array([t for t, _ in self._measured])
        meas = np.array([p for _, p in self._measured])
        fit = fit_delay(t_sent, sent, t_meas, meas, self.settings)
        if fit is None:
            return
        self._last_fit_s = now_s
        self.fits.append(fit)
        if not self.plausible(fit):
            return
        if self.delay_s is None:
            self.delay_s = fit.delay_s
        else:
            w = self.settings.smoothing
            self.delay_s = (1 - w) * self.delay_s + w * fit.delay_s


def lead_setpoint(
    setpoint: Setpoint, lead_s: float, jerk_mps3_enu: Vec3 = (0.0, 0.0, 0.0)
) -> Setpoint:
    """The setpoint ``lead_s`` [s] ahead along its own velocity, acceleration and jerk in
    [m/s^3] (constant jerk over the lead, so the acceleration, which the autopilot turns into
    tilt, is led too); a hold (v = a = j = 0) is unchanged."""
    if lead_s <= 0:
        return setpoint
    p = np.asarray(setpoint.position_m_enu, dtype=np.float64)
    v = np.asarray(setpoint.velocity_mps_enu, dtype=np.float64)
    a = np.asarray(setpoint.acceleration_mps2_enu, dtype=np.float64)
    j = np.asarray(jerk_mps3_enu, dtype=np.float64)
    return Setpoint(
        position_m_enu=_vec(p + v * lead_s + a * lead_s**2 / 2 + j * lead_s**3 / 6),
        velocity_mps_enu=_vec(v + a * lead_s + j * lead_s**2 / 2),
        acceleration_mps2_enu=_vec(a + j * lead_s),
        pen_down=setpoint.pen_down,
    )


def plan_jerk(previous: tuple[float, Setpoint] | None, now_s: float, setpoint: Setpoint) -> Vec3:
    """The plan's jerk in [m/s^3] between the previous setpoint (time [s], setpoint) and this
    one, clipped to +-:data:`JERK_MAX_MPS3`; zero without a previous one at most
    :data:`JERK_MAX_DT_S` before (a new plan starts from rest)."""
    if previous is None or not 0.0 < now_s - previous[0] <= JERK_MAX_DT_S:
        return (0.0, 0.0, 0.0)
    a0 = np.asarray(previous[1].acceleration_mps2_enu, dtype=np.float64)
    a1 = np.asarray(setpoint.acceleration_mps2_enu, dtype=np.float64)
    return _vec(np.clip((a1 - a0) / (now_s - previous[0]), -JERK_MAX_MPS3, JERK_MAX_MPS3))


def _vec(x: np.ndarray) -> Vec3:
    return (float(x[0]), float(x[1]), float(x[2]))

"""The autopilot's response delay: identified from flight data, compensated by leading the plan."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vehicle_agent.backends.base import Setpoint
from vehicle_agent.backends.mavlink.lag import (
    JERK_MAX_MPS3,
    DelayFit,
    LagSettings,
    ResponseDelayEstimator,
    fit_delay,
    lead_setpoint,
    plan_jerk,
)
from vehicle_agent.backends.mavlink.pen import PenOverBoard
from vehicle_agent.backends.mavlink.response import ResponseAid
from vehicle_agent.backends.mavlink.settings import MavlinkSettings
from vehicle_agent.backends.mavlink.snapshot import pen_reading
from vehicle_agent.backends.mavlink.truth import TruthSample
from vehicles.quadrotor_brush.autopilot_pen import BrushPen
from vehicles.quadrotor_brush.params import BrushParams

DT_S = 0.02


def path(t: np.ndarray, amplitude: float, w: float, phase: float) -> np.ndarray:
    """A smooth writing-like path (m) at times t (s): two sinusoids, not a straight line."""
    return np.column_stack(
        [amplitude * np.cos(w * t + phase), 0.6 * amplitude * np.sin(1.7 * w * t), np.ones_like(t)]
    )


@settings(max_examples=40, deadline=None)
@given(
    delay_s=st.floats(0.0, 0.3),
    amplitude=st.floats(0.1, 0.5),
    w=st.floats(0.8, 3.0),
    phase=st.floats(0.0, 6.28),
)
def test_fit_recovers_a_known_delay(
    delay_s: float, amplitude: float, w: float, phase: float
) -> None:
    t = np.arange(0.0, 3.0, DT_S)
    sent = path(t, amplitude, w, phase)
    measured = path(t - delay_s, amplitude, w, phase)
    fit = fit_delay(t, sent, t, measured, LagSettings())
    assert fit is not None
    assert fit.delay_s == pytest.approx(delay_s, abs=0.004)
    assert fit.rms_m <= fit.rms_at_zero_m


def test_a_hover_tells_nothing() -> None:
    t = np.arange(0.0, 3.0, DT_S)
    still = np.tile([0.0, 0.0, 1.0], (t.size, 1)) + 1e-4 * np.sin(t)[:, None]
    assert fit_delay(t, still, t, still, LagSettings()) is None


def test_a_straight_leg_is_not_mistaken_for_an_offset() -> None:
    """Along a straight line a delay and a constant offset look alike; the fit has no offset."""
    t = np.arange(0.0, 3.0, DT_S)
    line = np.column_stack([0.4 * t, np.zeros_like(t), np.ones_like(t)])
    late = np.column_stack([0.4 * (t - 0.12), np.zeros_like(t), np.ones_like(t)])
    fit = fit_delay(t, line, t, late, LagSettings())
    assert fit is not None and fit.delay_s == pytest.approx(0.12, abs=0.003)


def test_lead_is_exact_for_constant_acceleration_and_leaves_a_hold_alone() -> None:
    p0, v0, a0 = np.array([0.1, -0.2, 1.0]), np.array([0.3, 0.1, 0.0]), np.array([-0.5, 0.2, 0.1])
    setpoint = Setpoint(tuple(p0), tuple(v0), tuple(a0), pen_down=True)
    led = lead_setpoint(setpoint, 0.12)
    assert led.position_m_enu == pytest.approx(tuple(p0 + v0 * 0.12 + 0.5 * a0 * 0.12**2))
    assert led.velocity_mps_enu == pytest.approx(tuple(v0 + a0 * 0.12))
    assert led.pen_down
    hold = Setpoint((1.0, 2.0, 3.0))
    assert lead_setpoint(hold, 0.12) == hold


def test_lead_along_the_plan_jerk_is_exact_for_a_cubic_and_leads_the_acceleration() -> None:
    """A cubic path (constant jerk) led by 0.08 s lands on the path 0.08 s later, acceleration
    included: the tilt the autopilot makes of it is led as well."""
    jerk = np.array([2.0, -1.0, 0.5])

    def at(t: float) -> Setpoint:
        return Setpoint(tuple(jerk * t**3 / 6), tuple(jerk * t**2 / 2), tuple(jerk * t))

    previous = (0.49, at(0.49))
    measured = plan_jerk(previous, 0.5, at(0.5))
    assert measured == pytest.approx(tuple(jerk))
    led = lead_setpoint(at(0.5), 0.08, measured)
    later = at(0.58)
    assert led.position_m_enu == pytest.approx(later.position_m_enu, abs=1e-9)
    assert led.velocity_mps_enu == pytest.approx(later.velocity_mps_enu, abs=1e-9)
    assert led.acceleration_mps2_enu == pytest.approx(later.acceleration_mps2_enu, abs=1e-9)
    # no jerk across a gap (a new plan) or from a jump of the acceleration
    assert plan_jerk((0.3, at(0.3)), 0.5, at(0.5)) == (0.0, 0.0, 0.0)
    assert plan_jerk(None, 0.5, at(0.5)) == (0.0, 0.0, 0.0)
    jump = Setpoint((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (5.0, 0.0, 0.0))
    assert plan_jerk((0.49, at(0.0)), 0.5, jump)[0] == JERK_MAX_MPS3


def delayed_response(
    delay_s: float, lead: bool, seconds: float = 8.0
) -> tuple[float, float | None]:
    """Fly a circle through a plant that is the setpoint ``delay_s`` late; (RMS error to the
    plan in the last 3 s [m], identified delay [s])."""
    estimator = ResponseDelayEstimator()
    r, w = 0.3, 2 * math.pi / 4.0
    history: list[tuple[float, np.ndarray]] = []
    errors = []
    for k in range(int(seconds / DT_S)):
        now = k * DT_S
        c, s = math.cos(w * now), math.sin(w * now)
        plan = Setpoint((r * c, r * s, 1.0), (-r * w * s, r * w * c, 0.0),
                        (-r * w * w * c, -r * w * w * s, 0.0))  # fmt: skip
        target = lead_setpoint(plan, estimator.delay_s or 0.0) if lead else plan
        history.append((now, np.array(target.position_m_enu)))
        estimator.sent(now, target.position_m_enu)
        t_hist = np.array([h[0] for h in history])
        sent = np.array([h[1] for h in history])
        here = [float(np.interp(now - delay_s, t_hist, sent[:, i])) for i in range(3)]
        estimator.measured(now, (here[0], here[1], here[2]))
        if now > seconds - 3.0:
            errors.append(math.dist(here, plan.position_m_enu))
    return float(np.sqrt(np.mean(np.square(errors)))), estimator.delay_s


def test_closed_loop_identifies_the_lag_and_leading_cancels_most_of_it() -> None:
    late, _ = delayed_response(0.12, lead=False)
    led, identified = delayed_response(0.12, lead=True)
    assert identified == pytest.approx(0.12, abs=0.01)
    assert late > 0.05  # 0.47 m/s along a 0.3 m circle, 0.12 s late: 5.6 cm
    assert led < 0.1 * late


def test_a_climb_that_lags_unlike_a_delay_does_not_hide_the_horizontal_delay() -> None:
    """ArduCopter's thrust loop trails a climb by a steady few centimetres (a ramp through a P
    loop), not by a delay; the horizontal response is the delay to lead by."""
    t = np.arange(0.0, 3.0, DT_S)
    sent = path(t, 0.3, 2.0, 0.0)
    sent[:, 2] = 1.0 + 0.3 * t  # climbing at 0.3 m/s
    measured = path(t - 0.06, 0.3, 2.0, 0.0)
    measured[:, 2] = sent[:, 2] - 0.03 * (1.0 - np.exp(-t / 0.2))  # 3 cm behind, settling
    fit = fit_delay(t, sent, t, measured, LagSettings())
    assert fit is not None and fit.delay_s == pytest.approx(0.06, abs=0.004)
    assert ResponseDelayEstimator().plausible(fit)


def test_a_response_that_is_no_delay_leaves_the_lead_alone() -> None:
    """A vehicle that does not follow (here: stuck) fits the longest delay; it is not taken."""
    estimator = ResponseDelayEstimator()
    for k in range(200):
        t = k * DT_S
        estimator.sent(t, (0.3 * math.cos(t), 0.3 * math.sin(t), 1.0))
        estimator.measured(t, (0.3, 0.0, 1.0))
    assert estimator.fits and estimator.delay_s is None


def test_the_lag_is_fitted_on_the_truth_when_the_backend_has_it() -> None:
    """An estimate that trails the vehicle (PX4 SIH's by about 0.02 s) is not what the brush
    follows: with the simulator's truth at hand the fitted delay is the truth's."""
    aid = ResponseAid(MavlinkSettings(url="udpin:127.0.0.1:1", origin_m_enu=(0.0, 0.0, 0.0),
                                      truth="sitl"))  # fmt: skip
    assert aid.truth is not None
    for k in range(400):
        t = k * DT_S
        sent = path(np.array([t]), 0.3, 2.0, 0.0)[0]
        truth = path(np.array([t - 0.05]), 0.3, 2.0, 0.0)[0]
        estimate = path(np.array([t - 0.07]), 0.3, 2.0, 0.0)[0]
        aid.truth.samples.append(TruthSample(t, tuple(truth), (0.0, 0.0, 0.0)))
        aid.sent(t, tuple(sent))
        aid.measured(t, tuple(estimate), aid.true_state(t), None)
    assert aid.lag.delay_s == pytest.approx(0.05, abs=0.004)
    stale = ResponseAid(MavlinkSettings(url="udpin:127.0.0.1:1", origin_m_enu=(0.0, 0.0, 0.0)))
    for k in range(400):
        t = k * DT_S
        stale.sent(t, tuple(path(np.array([t]), 0.3, 2.0, 0.0)[0]))
        stale.measured(
            t, tuple(path(np.array([t - 0.07]), 0.3, 2.0, 0.0)[0]), stale.true_state(t), None
        )
    assert stale.lag.delay_s == pytest.approx(0.07, abs=0.004)


@pytest.mark.parametrize("pressing", [True, False])
def test_the_lag_is_fitted_on_the_pen_tip_which_trails_a_vehicle_leaning_into_its_drag(
    pressing: bool,
) -> None:
    """A vehicle leans into its drag by ``k`` [rad] per m/s, so the brush pressed on the board
    ``lever`` below it trails its body by ``lever * k`` times the velocity: to the writing, a
    further delay of ``lever * k``, which the lead must cover (on the body alone the fit says
    0.05 s). The brush in the air writes nothing: there the body's delay is the lead (a transit's
    acceleration swings the tip by 3 cm, which is no delay)."""
    brush = BrushParams()
    lever_m = brush.length_m - 0.01 if pressing else 0.5
    pen = PenOverBoard(BrushPen(brush, 1.0 - lever_m))  # the path flies at 1 m
    lean_rad_per_mps = 0.05
    aid = ResponseAid(MavlinkSettings(url="udpin:127.0.0.1:1", origin_m_enu=(0.0, 0.0, 0.0),
                                      truth="sitl"))  # fmt: skip
    assert aid.truth is not None
    for k in range(400):
        t = k * DT_S
        body = path(np.array([t - 0.05]), 0.3, 2.0, 0.0)[0]
        velocity = (path(np.array([t - 0.05 + 1e-4]), 0.3, 2.0, 0.0)[0] - body) / 1e-4
        # NED attitude, heading north: roll right to go east, nose down to go north
        lean = (lean_rad_per_mps * velocity[0], -lean_rad_per_mps * velocity[1], 0.0)
        aid.truth.samples.append(TruthSample(t, tuple(body), lean))
        aid.sent(t, tuple(path(np.array([t]), 0.3, 2.0, 0.0)[0]))
        truth = aid.true_state(t)
        aid.measured(t, tuple(body), truth, pen_reading(pen, tuple(body), None, truth))
    expected_s = 0.05 + (lever_m * lean_rad_per_mps if pressing else 0.0)
    assert aid.lag.delay_s == pytest.approx(expected_s, abs=0.004)


def test_a_delay_is_identified_only_by_a_clear_fit_and_then_refined_by_weaker_ones() -> None:
    """A fit leaving two thirds of the error (a transient on a loop with no delay) does not set a
    lead; once a clear fit has set one, such fits (slow writing legs, where the vehicle's wander
    is as large as the delay) refine it, and a fit leaving more than 0.8 never counts."""
    estimator = ResponseDelayEstimator()
    weak = DelayFit(0.05, rms_m=0.0059, rms_at_zero_m=0.0088)
    clear = DelayFit(0.09, rms_m=0.004, rms_at_zero_m=0.012)
    assert not estimator.plausible(weak) and estimator.plausible(clear)
    estimator.delay_s = clear.delay_s
    assert estimator.plausible(weak)
    assert not estimator.plausible(DelayFit(0.05, rms_m=0.0085, rms_at_zero_m=0.01))

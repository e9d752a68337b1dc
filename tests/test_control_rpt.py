"""RPT outer loop (Phang 2015 eq. 6-9): gains, closed-loop poles, steady-state error."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from vehicles.quadrotor_brush.control.errors import ControlError
from vehicles.quadrotor_brush.control.rpt import (
    DEFAULT_GAINS,
    PAPER_GAINS,
    RptAxisGains,
    augmented_system,
    closed_loop_matrix,
)


def test_paper_feedback_row_has_the_published_numbers() -> None:
    """eps = 1, w_n = 1.772, zeta = 0.5, k_i = 0.2: F_aug of eq. 8."""
    f = PAPER_GAINS.x.feedback_row()
    kp = 1.772**2 + 2 * 0.5 * 1.772 * 0.2
    kd = 2 * 0.5 * 1.772 + 0.2
    assert f == pytest.approx([0.2 * 1.772**2, kp, kd, 1.0, -kp, -kd])
    assert PAPER_GAINS.z.feedback_row()[1] == pytest.approx(2.089**2 + 2 * 0.66 * 2.089 * 0.23)


def closed_loop_poles(gains: RptAxisGains) -> np.ndarray:
    eig = np.linalg.eigvals(closed_loop_matrix(gains))
    return np.sort_complex(eig[np.abs(eig) > 1e-6])


@pytest.mark.parametrize("gains", [PAPER_GAINS.x, PAPER_GAINS.z, DEFAULT_GAINS.x, DEFAULT_GAINS.z])
def test_closed_loop_poles_are_the_designed_ones(gains: RptAxisGains) -> None:
    eig = np.linalg.eigvals(closed_loop_matrix(gains))
    assert np.sum(np.abs(eig) < 1e-6) == 3  # the reference generator p_r, v_r, a_r
    assert closed_loop_poles(gains) == pytest.approx(gains.designed_poles(), abs=1e-9)
    real_pole = [p for p in gains.designed_poles() if abs(p.imag) < 1e-12]
    assert real_pole[0].real == pytest.approx(-gains.ki_radps / gains.eps)


def test_the_printed_integrator_sign_would_be_unstable() -> None:
    """Eq. 7 prints d f/dt = p - p_r; with the printed F_aug that loop has a pole at +0.163."""
    a, b = augmented_system()
    a[0, 1], a[0, 4] = -1.0, 1.0
    eig = np.linalg.eigvals(a + b @ PAPER_GAINS.x.feedback_row()[None, :])
    assert max(eig.real) == pytest.approx(0.1634, abs=1e-3)


@settings(max_examples=40, deadline=None)
@given(
    eps=st.floats(0.05, 2.0),
    wn=st.floats(0.5, 10.0),
    zeta=st.floats(0.2, 1.5),
    ki=st.floats(0.05, 3.0),
)
@example(eps=0.5, wn=0.5, zeta=0.5, ki=0.25)  # three poles with one real part
def test_poles_scale_with_one_over_eps(eps: float, wn: float, zeta: float, ki: float) -> None:
    base = RptAxisGains(1.0, wn, zeta, ki)
    fast = RptAxisGains(eps, wn, zeta, ki)
    assert np.all(closed_loop_poles(fast).real < 0.0)
    # compared through their polynomial: order-free, and well conditioned where the poles
    # coincide (wn 0.5, zeta 0.5, ki 0.25: three poles with one real part, sorted by noise)
    scaled = np.poly(closed_loop_poles(base) / eps).real
    assert np.poly(closed_loop_poles(fast)).real == pytest.approx(scaled, rel=1e-6)


def simulate_constant_disturbance(gains: RptAxisGains, disturbance: float, t_end: float) -> float:
    """Discrete 100 Hz RPT on a double integrator pushed by a constant force; final error."""
    dt = 0.01
    kint, kp, kd = gains.integral_gain, gains.position_gain, gains.velocity_gain
    p = v = integral = 0.0
    ref = 0.3
    for _ in range(int(t_end / dt)):
        error = ref - p
        integral += error * dt
        u = kint * integral + kp * error - kd * v
        v += (u + disturbance) * dt
        p += v * dt
    return ref - p


@pytest.mark.parametrize(("gains", "t_end"), [(PAPER_GAINS.x, 80.0), (DEFAULT_GAINS.x, 40.0)])
def test_zero_steady_state_error_under_a_constant_disturbance(
    gains: RptAxisGains, t_end: float
) -> None:
    assert abs(simulate_constant_disturbance(gains, 0.5, t_end)) < 1e-4


def test_default_gains_are_faster_but_well_inside_the_inner_loop() -> None:
    assert DEFAULT_GAINS.x.bandwidth_radps > 1.5 * PAPER_GAINS.x.bandwidth_radps
    assert DEFAULT_GAINS.z.bandwidth_radps < 25.0 / 5.0


def test_bad_gains_name_the_field() -> None:
    with pytest.raises(ControlError, match="zeta"):
        RptAxisGains(1.0, 1.0, -0.5, 0.1)


def test_controller_command_is_f_aug_times_x_aug() -> None:
    """The paper's controller outputs u = F_aug x_aug per axis (eq. 8) on its own estimates."""
    from vehicles.quadrotor_brush.control.config import PAPER_CONFIG
    from vehicles.quadrotor_brush.control.controller import PositionController, ReferenceTick

    ctrl = PositionController(PAPER_CONFIG, 0.01, np.zeros((2, 3)))
    rng = np.random.default_rng(0)
    for _ in range(30):
        ref = ReferenceTick(
            rng.normal(size=(2, 3)), rng.normal(size=(2, 3)), rng.normal(size=(2, 3))
        )
        ctrl.update(rng.normal(scale=0.01, size=(2, 3)), ref)
        est = ctrl.estimator
        for i in range(2):
            for axis, gains in enumerate(PAPER_GAINS.axes()):
                x_aug = [
                    ctrl.integral_m_s[i, axis],
                    ref.position_m_enu[i, axis],
                    ref.velocity_mps_enu[i, axis],
                    ref.acceleration_mps2_enu[i, axis],
                    est.position_m_enu[i, axis],
                    est.velocity_mps_enu[i, axis],
                ]
                expected = float(gains.feedback_row() @ np.array(x_aug))
                assert ctrl.accel_cmd_mps2_enu[i, axis] == pytest.approx(expected, abs=1e-12)

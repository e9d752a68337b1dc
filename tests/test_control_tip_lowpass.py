"""The brush-tip preview's low-pass (``vehicles/quadrotor_brush/control/tip.py``), written in
place of ``scipy.signal.lfilter`` so that a planning worker need not import ``scipy.signal``: the
same filter, on any length (across the blocks it is computed by), any trailing shape and any
pole in [0, 1]; a step's response is the known ``1 - alpha^(k+1)``."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.signal import lfilter

from vehicles.quadrotor_brush.control.tip import LOWPASS_BLOCK, lowpass_at_rest

SIGNALS = st.tuples(
    st.integers(1, 3 * LOWPASS_BLOCK + 5), st.sampled_from([(), (1,), (2, 3)])
).flatmap(
    lambda shape: arrays(
        np.float64,
        (shape[0], *shape[1]),
        elements=st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False),
    )
)


@settings(max_examples=300, deadline=None)
@given(
    signal=SIGNALS,
    alpha=st.one_of(st.floats(0.0, 1.0), st.sampled_from([0.0, 0.89, 0.999, 1.0])),
)
def test_the_lowpass_is_scipys_lfilter_at_rest(signal: np.ndarray, alpha: float) -> None:
    expected = lfilter([1.0 - alpha], [1.0, -alpha], signal, axis=0, zi=alpha * signal[:1])[0]
    got = lowpass_at_rest(signal, alpha)
    assert got.shape == signal.shape
    scale = max(1.0, float(np.max(np.abs(signal))))
    np.testing.assert_allclose(got, expected, rtol=0.0, atol=1e-12 * scale)


def test_a_step_rises_as_one_minus_the_pole_to_the_power_of_its_samples() -> None:
    alpha, n = 0.89, 5 * LOWPASS_BLOCK + 7
    step = np.ones(n)
    step[0] = 0.0  # at rest on zero, then one from the second sample on
    k = np.arange(n - 1)
    np.testing.assert_allclose(lowpass_at_rest(step, alpha)[1:], 1.0 - alpha ** (k + 1), atol=1e-14)
    assert lowpass_at_rest(step, alpha)[0] == 0.0

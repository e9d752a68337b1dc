"""Aim the brush tip, not the body: a preview filter on the horizontal reference.

The brush hangs along the body z axis, ``lever`` below the vehicle reference point. The horizontal
thrust per unit mass must carry the acceleration and the linear drag, ``p'' + c p'``, so the body
tilts by that over g and the tip writes at ``p_tip = p - lever (p'' + c p') / g`` (small angles).
For the tip to follow ``r(t)`` the body must follow the solution of
``p - tau^2 (p'' + c p') = r``, ``tau^2 = lever / g``. Its transfer function has one stable and one
unstable pole, ``a / (s + a) * b / (b - s)``: a first-order low-pass run forward and another run
backward over the whole reference, which is known in advance (a two-sided exponential kernel;
with c = 0 both time constants are tau). Being linear and time-invariant it maps velocity and
acceleration references the same way.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from vehicles.quadrotor_brush.control.errors import ControlError

FloatArray = NDArray[np.float64]


def tip_filter_poles(
    lever_m: float, drag_per_s: float, gravity_mps2: float = 9.81
) -> tuple[float, float]:
    """(a, b) in [1/s] with ``1 / (1 - tau^2 (s^2 + c s)) = a / (s + a) * b / (b - s)``,
    ``tau^2 = lever / g``."""
    if not lever_m > 0.0:
        raise ControlError("must be positive", field="lever_m")
    tau2 = lever_m / gravity_mps2
    root = math.sqrt(drag_per_s**2 + 4.0 / tau2)
    return 0.5 * (drag_per_s + root), 0.5 * (root - drag_per_s)


LOWPASS_BLOCK = 64
"""Samples per block of :func:`lowpass_at_rest`: each block's response to its own input is one
(B x B) matrix product, and only the state between blocks is carried in a Python loop (K / B
steps). With ``alpha <= 1`` every weight is at most 1, so the rounding stays within a few ulp
of the magnitude whatever B; 64 keeps the matrix at 32 KiB and the loop short."""


def lowpass_at_rest(signal: FloatArray, alpha: float) -> FloatArray:
    """``y[k] = alpha y[k-1] + (1 - alpha) x[k]`` along axis 0, at rest before the start
    (``y[-1] = x[0]``): exactly the recursion, not a truncated kernel, computed by blocks.

    Written here rather than imported: ``scipy.signal.lfilter`` with ``zi = alpha x[0]`` is the
    same filter, but importing ``scipy.signal`` cost every planning worker 45 MiB and 0.6 s
    (issue 35)."""
    x = np.asarray(signal, dtype=np.float64)
    n = x.shape[0]
    if n == 0:
        return x.copy()
    columns = x.reshape(n, -1)
    n_blocks = -(-n // LOWPASS_BLOCK)
    padded = np.empty((n_blocks * LOWPASS_BLOCK, columns.shape[1]))
    padded[:n] = columns
    padded[n:] = columns[-1]  # past the end: feeds only outputs that are dropped
    blocks = padded.reshape(n_blocks, LOWPASS_BLOCK, -1)
    lag = np.subtract.outer(np.arange(LOWPASS_BLOCK), np.arange(LOWPASS_BLOCK))
    kernel = np.where(lag >= 0, (1.0 - alpha) * alpha ** np.maximum(lag, 0), 0.0)
    decay = (alpha ** np.arange(1, LOWPASS_BLOCK + 1))[:, None]  # the state's share, by row
    out = kernel @ blocks  # each block's response from rest
    state = columns[0]
    for block in out:
        block += decay * state
        state = block[-1]
    result: FloatArray = out.reshape(-1, columns.shape[1])[:n].reshape(x.shape)
    return result


def _two_sided_lowpass(
    signal: FloatArray, forward_alpha: float, backward_alpha: float
) -> FloatArray:
    """First-order low-pass forward, then another backward, along axis 0, at rest on the ends."""
    forward = lowpass_at_rest(signal, forward_alpha)
    result: FloatArray = lowpass_at_rest(forward[::-1], backward_alpha)[::-1]
    return result


def body_reference_for_tip(
    position_m_enu: FloatArray,
    velocity_mps_enu: FloatArray,
    acceleration_mps2_enu: FloatArray,
    dt_s: float,
    lever_m: float,
    gravity_mps2: float = 9.81,
    drag_per_s: tuple[float, float] = (0.0, 0.0),
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Body reference (p, v, a) whose tilt puts the brush tip on the given reference.

    Arrays of shape (K, ..., 3) sampled every ``dt_s`` along axis 0; only x and y change. The
    reference should start and end at rest (the filter assumes constant values beyond the ends).
    ``drag_per_s`` is the known linear drag per unit mass of x and y: the thrust, hence the tilt,
    must also carry ``c v``.
    """
    if lever_m == 0.0:
        return position_m_enu, velocity_mps_enu, acceleration_mps2_enu
    out = [
        np.array(ref, dtype=np.float64, copy=True)
        for ref in (position_m_enu, velocity_mps_enu, acceleration_mps2_enu)
    ]
    for axis in (0, 1):
        a, b = tip_filter_poles(lever_m, drag_per_s[axis], gravity_mps2)
        fa, fb = math.exp(-a * dt_s), math.exp(-b * dt_s)
        for shifted in out:
            shifted[..., axis] = _two_sided_lowpass(shifted[..., axis], fa, fb)
    return out[0], out[1], out[2]


def lag_compensated(
    acceleration_mps2_enu: FloatArray,
    dt_s: float,
    lead_s: ArrayLike,
    second_order_s2: ArrayLike | None = None,
) -> FloatArray:
    """Acceleration feed-forward that inverts the inner loop: ``a + c1 a' + c2 a''`` per axis.

    The inner loop and motors deliver a commanded acceleration through roughly
    ``1 / (c2 s^2 + c1 s + 1)`` (``c1 = 2 zeta / w_n`` plus half a tick of hold,
    ``c2 = 1 / w_n^2``); the reference is known in advance, so its derivatives lead the command.
    ``lead_s`` and ``second_order_s2`` have one entry per axis (3,).
    """
    if acceleration_mps2_enu.shape[0] < 3:
        return acceleration_mps2_enu
    rate = np.gradient(acceleration_mps2_enu, dt_s, axis=0)
    led: FloatArray = acceleration_mps2_enu + np.asarray(lead_s, dtype=np.float64) * rate
    if second_order_s2 is not None:
        curvature = np.gradient(rate, dt_s, axis=0)
        led = led + np.asarray(second_order_s2, dtype=np.float64) * curvature
    return led

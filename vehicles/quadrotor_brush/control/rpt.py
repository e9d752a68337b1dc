"""Robust and perfect tracking (RPT) outer loop per axis, Phang et al. 2015 eq. 6-9.

Per axis the nominal plant is a double integrator (eq. 6). Augmented with the error integral, the
state is ``x_aug = [f(p_e), p_r, v_r, a_r, p, v]`` (eq. 7) and the law ``u = F_aug x_aug`` (eq. 8)
places the closed-loop poles at the roots of ``p_i(eps s)`` with
``p_i(s) = (s + k_i)(s^2 + 2 zeta w_n s + w_n^2)`` (eq. 9), i.e. the designed poles divided by eps.

Two notes on the printed equations, both immaterial at the paper's eps = 1:

- eq. 7 prints the integrator row as ``d f/dt = p - p_r``; with the printed ``F_aug`` that loop has
  an unstable real pole (+0.163 for the x, y gains). We integrate ``p_e = p_r - p``, as the name
  ``f(p_e)`` says, which gives exactly the poles of eq. 9.
- the printed integral gain ``k_i w_n^2`` carries no ``1/eps^3``; the pole scaling by ``1/eps``
  that eq. 9 describes needs it, so we use ``k_i w_n^2 / eps^3``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from vehicles.quadrotor_brush.control.errors import ControlError

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]


@dataclass(frozen=True)
class RptAxisGains:
    """Design parameters of one axis (eq. 9)."""

    eps: float
    """Time-scale parameter: poles are the designed ones divided by eps."""
    wn_radps: float
    """Natural frequency of the complex pole pair in [rad/s] (at eps = 1)."""
    zeta: float
    """Damping ratio of the complex pole pair."""
    ki_radps: float
    """Location of the real (integral) pole in [rad/s] (at eps = 1)."""

    def __post_init__(self) -> None:
        for name in ("eps", "wn_radps", "zeta", "ki_radps"):
            value = getattr(self, name)
            if not (value > 0.0 and np.isfinite(value)):
                raise ControlError(f"must be positive and finite, got {value!r}", field=name)

    @property
    def integral_gain(self) -> float:
        """Gain on the error integral in [1/s^3]: k_i w_n^2 / eps^3."""
        return self.ki_radps * self.wn_radps**2 / self.eps**3

    @property
    def position_gain(self) -> float:
        """Gain on the position error in [1/s^2]: (w_n^2 + 2 zeta w_n k_i) / eps^2."""
        w, z, k = self.wn_radps, self.zeta, self.ki_radps
        return (w * w + 2.0 * z * w * k) / self.eps**2

    @property
    def velocity_gain(self) -> float:
        """Gain on the velocity error in [1/s]: (2 zeta w_n + k_i) / eps."""
        return (2.0 * self.zeta * self.wn_radps + self.ki_radps) / self.eps

    def feedback_row(self) -> FloatArray:
        """F_aug of eq. 8 acting on ``[f(p_e), p_r, v_r, a_r, p, v]``."""
        kp, kd = self.position_gain, self.velocity_gain
        return np.array([self.integral_gain, kp, kd, 1.0, -kp, -kd])

    def designed_poles(self) -> ComplexArray:
        """Roots of p_i(eps s) (eq. 9 scaled by 1/eps), sorted."""
        poly = np.polymul(
            [1.0, self.ki_radps], [1.0, 2.0 * self.zeta * self.wn_radps, self.wn_radps**2]
        )
        roots: ComplexArray = np.sort_complex(np.roots(poly).astype(np.complex128) / self.eps)
        return roots

    @property
    def bandwidth_radps(self) -> float:
        """Largest designed pole magnitude in [rad/s]."""
        return float(np.max(np.abs(self.designed_poles())))


@dataclass(frozen=True)
class RptGains:
    """Gains of the three world axes."""

    name: str
    """Short label for reports, e.g. ``"paper"``."""
    x: RptAxisGains
    """East axis."""
    y: RptAxisGains
    """North axis."""
    z: RptAxisGains
    """Up axis."""

    def axes(self) -> tuple[RptAxisGains, RptAxisGains, RptAxisGains]:
        """(x, y, z)."""
        return (self.x, self.y, self.z)

    def vectors(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(integral, position, velocity) gains as (3,) arrays over x, y, z."""
        axes = self.axes()
        return (
            np.array([a.integral_gain for a in axes]),
            np.array([a.position_gain for a in axes]),
            np.array([a.velocity_gain for a in axes]),
        )

    def to_json_dict(self) -> dict[str, object]:
        """Plain dict for metrics files."""
        return {
            "name": self.name,
            **{
                key: {"eps": a.eps, "wn": a.wn_radps, "zeta": a.zeta, "ki": a.ki_radps}
                for key, a in zip("xyz", self.axes(), strict=True)
            },
        }

    def with_eps(self, eps_xy: float, eps_z: float, name: str) -> RptGains:
        """The same pole pattern, time-scaled by new eps values."""
        return RptGains(
            name,
            RptAxisGains(eps_xy, self.x.wn_radps, self.x.zeta, self.x.ki_radps),
            RptAxisGains(eps_xy, self.y.wn_radps, self.y.zeta, self.y.ki_radps),
            RptAxisGains(eps_z, self.z.wn_radps, self.z.zeta, self.z.ki_radps),
        )


_PAPER_XY = RptAxisGains(eps=1.0, wn_radps=1.772, zeta=0.5, ki_radps=0.2)
_PAPER_Z = RptAxisGains(eps=1.0, wn_radps=2.089, zeta=0.66, ki_radps=0.23)

PAPER_GAINS = RptGains("paper", _PAPER_XY, _PAPER_XY, _PAPER_Z)
"""The published set (Phang 2015 section 3), tuned indoors without wind."""

DEFAULT_GAINS = PAPER_GAINS.with_eps(0.6, 0.6, "default")
"""The shipped set: the paper's pole pattern made 1/0.6 times faster (complex poles at 2.95 rad/s
for x, y and 3.5 rad/s for z), an eighth of the 25 rad/s inner loop. With the disturbance
cancellation of the default controller it stays stable down to an inner loop of about 15 rad/s;
eps 0.3 wrote marginally better nominally but went unstable there."""


def augmented_system() -> tuple[FloatArray, FloatArray]:
    """(A_aug, B_aug) of eq. 7 with the integrator row integrating p_e = p_r - p."""
    a = np.zeros((6, 6))
    a[0, 1], a[0, 4] = 1.0, -1.0
    a[1, 2] = a[2, 3] = a[4, 5] = 1.0
    b = np.zeros((6, 1))
    b[5, 0] = 1.0
    return a, b


def closed_loop_matrix(gains: RptAxisGains) -> FloatArray:
    """A_aug + B_aug F_aug: its non-zero eigenvalues are the designed poles; the three zero ones
    belong to the reference generator (p_r, v_r, a_r)."""
    a, b = augmented_system()
    closed: FloatArray = a + b @ gains.feedback_row()[None, :]
    return closed

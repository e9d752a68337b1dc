"""The sponge pen: a calibrated polynomial from normal contact force to line width, both ways.

The paper (Guo et al. 2024, Fig. 4c) calibrates its sponge pen by drawing lines at several forces
and fitting a polynomial; the figure's numbers are not in the text, so the default curve here is a
quadratic of the same shape (width grows with force, flattening as the sponge saturates) over the
force range the figure spans: about 5 mm at 1 N to 14 mm at 6 N.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from planner.errors import PlannerError
from vehicles.hexarotor_sponge import defaults

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class PenCurve:
    """Line width as a polynomial of normal force, valid on ``[force_min_n, force_max_n]``."""

    coefficients_m: tuple[float, ...] = defaults.PEN_WIDTH_COEFFICIENTS_M
    """Polynomial coefficients, lowest order first: width [m] = sum c_k F^k with F in [N]."""
    force_min_n: float = defaults.PEN_FORCE_MIN_N
    """Lowest calibrated normal force in [N] (below it the sponge leaves no reliable line)."""
    force_max_n: float = defaults.PEN_FORCE_MAX_N
    """Highest calibrated normal force in [N]."""

    def __post_init__(self) -> None:
        if not 0.0 < self.force_min_n < self.force_max_n:
            raise PlannerError("need 0 < force_min_n < force_max_n", field="pen")
        grid = np.linspace(self.force_min_n, self.force_max_n, 201)
        if np.any(np.diff(self.width_m(grid)) <= 0.0) or self.width_m(grid)[0] <= 0.0:
            raise PlannerError(
                "the pen curve must give positive widths that grow with force on its range",
                field="pen",
            )

    @property
    def width_min_m(self) -> float:
        """Narrowest line in [m] the pen draws (at ``force_min_n``)."""
        return float(self.width_m(np.array([self.force_min_n]))[0])

    @property
    def width_max_m(self) -> float:
        """Widest line in [m] the pen draws (at ``force_max_n``)."""
        return float(self.width_m(np.array([self.force_max_n]))[0])

    def width_m(self, force_n: FloatArray) -> FloatArray:
        """Ink width in [m] for normal forces in [N]; 0 where the force is not positive, fading
        linearly to 0 below ``force_min_n``.

        Forces beyond the calibrated range are clamped to it (the sponge gives no wider line).
        """
        f = np.asarray(force_n, dtype=np.float64)
        clamped = np.clip(f, self.force_min_n, self.force_max_n)
        width = np.polynomial.polynomial.polyval(clamped, np.asarray(self.coefficients_m))
        below = np.clip(f / self.force_min_n, 0.0, 1.0)
        faded = width * np.where(f < self.force_min_n, below, 1.0)
        return np.asarray(np.where(f > 0.0, faded, 0.0))

    def force_n(self, width_m: FloatArray) -> FloatArray:
        """Normal force in [N] that draws each wanted width in [m] (inverse of :meth:`width_m`).

        Raises :class:`PlannerError` naming the first width outside the pen's range.
        """
        w = np.asarray(width_m, dtype=np.float64)
        bad = np.flatnonzero(
            ~np.isfinite(w) | (w < self.width_min_m - 1e-9) | (w > self.width_max_m + 1e-9)
        )
        if bad.size:
            raise PlannerError(
                f"width {w.flat[bad[0]] * 1e3:.2f} mm is outside the pen's range "
                f"{self.width_min_m * 1e3:.2f}..{self.width_max_m * 1e3:.2f} mm",
                point_index=int(bad[0]),
                field="w",
            )
        return self._invert(np.clip(w, self.width_min_m, self.width_max_m))

    def clamp_width_m(self, width_m: FloatArray) -> tuple[FloatArray, int]:
        """Wanted widths clamped to the pen's range, and how many were changed."""
        w = np.asarray(width_m, dtype=np.float64)
        clamped = np.clip(w, self.width_min_m, self.width_max_m)
        return clamped, int(np.count_nonzero(np.abs(clamped - w) > 1e-12))

    def _invert(self, width_m: FloatArray) -> FloatArray:
        """Bisection on the monotone polynomial (vectorised, 50 halvings: below 1e-13 N)."""
        lo = np.full(width_m.shape, self.force_min_n)
        hi = np.full(width_m.shape, self.force_max_n)
        coeffs = np.asarray(self.coefficients_m)
        for _ in range(50):
            mid = 0.5 * (lo + hi)
            low_side = np.polynomial.polynomial.polyval(mid, coeffs) < width_m
            lo = np.where(low_side, mid, lo)
            hi = np.where(low_side, hi, mid)
        return np.asarray(0.5 * (lo + hi))

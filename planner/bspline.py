"""Clamped normalized uniform cubic B-spline (Phang et al. 2015, section 5.1, eq. 16-30, 45-52).

Conventions (the paper is loose about the count ``M``; this module fixes one consistent choice):

- ``n_spans`` (``m`` below) unit spans in the spline parameter ``u``; knot vector
  ``[0, 0, 0, 0, 1, 2, ..., m-1, m, m, m, m]`` (``m + 7`` knots);
- ``n_ctrl = m + 3`` basis functions / control points ``tau_0 .. tau_{m+2}``. The first and last
  three control points fix position, velocity and acceleration at the ends (eq. 38, 54);
- time ``t`` in [0, T] maps to ``u = alpha * t`` with ``alpha = m / T`` (knots per second).

Cubic splines have 4 non-zero basis functions on each span. Every evaluation here is vectorised:
``first[i]`` is the index of the first non-zero basis at sample ``i`` and ``values[i, :]`` the 4
values (or their derivatives) for control points ``first[i] .. first[i] + 3``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from planner.coo import CooMatrix
from planner.errors import PlannerError

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

DEGREE = 3
_BOUNDARY_SPANS = 3  # spans whose bases differ from the interior B_3 (eq. 22-27) at each end


def knot_vector(n_spans: int) -> FloatArray:
    """Clamped knot vector ``[0,0,0,0,1,..,m-1,m,m,m,m]`` for ``m = n_spans`` unit spans."""
    if n_spans < 1:
        raise PlannerError(f"a spline needs at least one span, got {n_spans}", field="n_spans")
    inner = np.arange(n_spans + 1, dtype=np.float64)
    return np.concatenate([np.zeros(DEGREE), inner, np.full(DEGREE, float(n_spans))])


def cox_de_boor(knots: FloatArray, index: int, degree: int, u: float) -> float:
    """Reference scalar basis ``N_{index,degree}(u)`` by the recursion of eq. (16)-(17).

    Half-open spans, except that the last non-empty span is closed at its right end so that the
    basis is a partition of unity on the whole closed interval.
    """
    if degree == 0:
        lo, hi = knots[index], knots[index + 1]
        if lo <= u < hi:
            return 1.0
        last = knots[-1]
        return 1.0 if (u == last and hi == last and lo < hi) else 0.0
    value = 0.0
    den_left = knots[index + degree] - knots[index]
    if den_left > 0.0:
        value += (u - knots[index]) / den_left * cox_de_boor(knots, index, degree - 1, u)
    den_right = knots[index + degree + 1] - knots[index + 1]
    if den_right > 0.0:
        value += (
            (knots[index + degree + 1] - u)
            / den_right
            * cox_de_boor(knots, index + 1, degree - 1, u)
        )
    return value


def _span_coefficients_by_recursion(n_spans: int) -> FloatArray:
    """Polynomial coefficients ``C[s, a, p]``: basis ``s + a`` on span ``s`` is ``sum_p C x^p``.

    ``x = u - s`` in [0, 1]. A cubic is fixed by 4 samples, so sampling the recursion at 4
    interior points and solving the Vandermonde system is exact up to rounding.
    """
    knots = knot_vector(n_spans)
    x = np.array([0.125, 0.375, 0.625, 0.875])
    vandermonde_inv = np.linalg.inv(np.vander(x, 4, increasing=True))
    coeffs = np.empty((n_spans, 4, 4))
    for s in range(n_spans):
        for a in range(4):
            samples = np.array([cox_de_boor(knots, s + a, DEGREE, s + xi) for xi in x])
            coeffs[s, a, :] = vandermonde_inv @ samples
    return coeffs


@lru_cache(maxsize=8)
def _small_tables(n_spans: int) -> FloatArray:
    return _span_coefficients_by_recursion(n_spans)


@lru_cache(maxsize=64)
def span_coefficients(n_spans: int) -> FloatArray:
    """Per-span polynomial coefficients, shape ``(n_spans, 4, 4)``, cached per span count.

    For ``m >= 6`` the first and last three spans hold the clamped boundary bases (eq. 22-27) and
    all other spans the uniform basis ``B_3`` of eq. (21); the table is assembled from the
    ``m = 6`` reference so that large ``m`` costs no recursion.
    """
    if n_spans < 2 * _BOUNDARY_SPANS:
        return _small_tables(n_spans)
    reference = _small_tables(2 * _BOUNDARY_SPANS)
    coeffs = np.empty((n_spans, 4, 4))
    coeffs[:_BOUNDARY_SPANS] = reference[:_BOUNDARY_SPANS]
    coeffs[-_BOUNDARY_SPANS:] = reference[_BOUNDARY_SPANS:]
    coeffs[_BOUNDARY_SPANS:-_BOUNDARY_SPANS] = uniform_span_coefficients()
    coeffs.setflags(write=False)
    return coeffs


def uniform_span_coefficients() -> FloatArray:
    """Coefficients of the four pieces of the uniform cubic ``B_3`` (eq. 21) seen from one span.

    Row ``a`` is the piece of the basis that starts ``3 - a`` spans to the left.
    """
    return (
        np.array(
            [
                [1.0, -3.0, 3.0, -1.0],
                [4.0, 0.0, -6.0, 3.0],
                [1.0, 3.0, 3.0, -3.0],
                [0.0, 0.0, 0.0, 1.0],
            ]
        )
        / 6.0
    )


_POWER_DERIVATIVE_FACTORS = (
    np.array([1.0, 1.0, 1.0, 1.0]),
    np.array([0.0, 1.0, 2.0, 3.0]),
    np.array([0.0, 0.0, 2.0, 6.0]),
    np.array([0.0, 0.0, 0.0, 6.0]),
)


def _power_rows(x: FloatArray, derivative: int) -> FloatArray:
    """Rows ``d^k/dx^k [1, x, x^2, x^3]`` for each sample, shape (n, 4)."""
    n = x.shape[0]
    powers = np.zeros((n, 4))
    for p in range(derivative, 4):
        powers[:, p] = x ** (p - derivative)
    return np.asarray(powers * _POWER_DERIVATIVE_FACTORS[derivative])


@dataclass(frozen=True, eq=False)
class BasisRows:
    """The 4 non-zero basis values per sample: a compact, vectorised sparse matrix."""

    first: IntArray
    """Index of the first non-zero basis (control point) per sample, shape (n,)."""
    values: FloatArray
    """Values (or derivatives) of bases ``first .. first + 3`` per sample, shape (n, 4)."""
    n_ctrl: int
    """Number of control points (columns of the full matrix)."""

    def toarray(self) -> FloatArray:
        """Dense ``(n, n_ctrl)`` matrix (``H`` of eq. 35 for derivative 0)."""
        dense = np.zeros((self.first.shape[0], self.n_ctrl))
        rows = np.arange(self.first.shape[0])[:, None]
        dense[rows, self.first[:, None] + np.arange(4)[None, :]] = self.values
        return dense

    def apply(self, control_points: FloatArray) -> FloatArray:
        """Values ``sum_a values[:, a] * ctrl[first + a]``; ctrl shape (n_ctrl,) or (n_ctrl, d)."""
        idx = self.first[:, None] + np.arange(4)[None, :]
        gathered = control_points[idx]
        if control_points.ndim == 1:
            return np.asarray(np.einsum("na,na->n", self.values, gathered))
        return np.asarray(np.einsum("na,nad->nd", self.values, gathered))


def basis_rows(u: FloatArray, n_spans: int, derivative: int = 0) -> BasisRows:
    """Basis functions (or their ``derivative``-th derivative w.r.t. ``u``) at parameters ``u``.

    ``u`` is clipped to [0, n_spans]; ``u == n_spans`` belongs to the last span.
    """
    if not 0 <= derivative <= DEGREE:
        raise PlannerError(f"derivative order {derivative} not in 0..3", field="derivative")
    u = np.clip(np.asarray(u, dtype=np.float64).ravel(), 0.0, float(n_spans))
    span = np.minimum(np.floor(u).astype(np.int64), n_spans - 1)
    x = u - span
    table = span_coefficients(n_spans)
    values = np.einsum("nap,np->na", table[span], _power_rows(x, derivative))
    return BasisRows(first=span, values=values, n_ctrl=n_spans + DEGREE)


def basis_rows_pair(u: FloatArray, n_spans: int) -> tuple[BasisRows, BasisRows]:
    """Values and first derivatives (w.r.t. ``u``) at ``u``, sharing the span lookup."""
    u = np.clip(np.asarray(u, dtype=np.float64).ravel(), 0.0, float(n_spans))
    span = np.minimum(np.floor(u).astype(np.int64), n_spans - 1)
    x = u - span
    table = span_coefficients(n_spans)[span]
    powers = np.stack([_power_rows(x, 0), _power_rows(x, 1)])  # (2, n, 4)
    values = np.einsum("nap,knp->kna", table, powers)
    n_ctrl = n_spans + DEGREE
    return BasisRows(span, values[0], n_ctrl), BasisRows(span, values[1], n_ctrl)


# --- control-point difference operators (eq. 45-52) -------------------------------------------


def apply_band(values: FloatArray, x: FloatArray) -> FloatArray:
    """``B @ x`` for the band matrix ``B`` whose row ``i`` holds ``values[i]`` in columns
    ``i .. i + width - 1`` (the operators below), by shifted slices: each row's terms are summed
    in column order, as the :class:`CooMatrix` product sums them (the same numbers, bit for bit),
    without its gathers. ``x`` shape (n_cols,) or (n_cols, d)."""
    n_rows, width = values.shape
    columns = values if x.ndim == 1 else values[:, :, None]
    total = columns[:, 0] * x[:n_rows]
    for a in range(1, width):
        total = total + columns[:, a] * x[a : a + n_rows]
    return np.asarray(total)


def _band(values: FloatArray, n_cols: int) -> CooMatrix:
    """The matrix whose row ``i`` holds ``values[i]`` in columns ``i .. i + width - 1``."""
    n_rows, width = values.shape
    rows = np.repeat(np.arange(n_rows), width)
    cols = rows + np.tile(np.arange(width), n_rows)
    return CooMatrix(rows, cols, values.ravel(), (n_rows, n_cols))


def _difference_values(n_spans: int, order: int) -> FloatArray:
    """Row values ``[-s, s]`` of the ``order``-th hodograph difference (eq. 46 for 1, eq. 50 for
    2): ``s = (4 - order) / (knot[i + 4] - knot[i + order])``."""
    knots = knot_vector(n_spans)
    i = np.arange(n_spans + DEGREE - order)
    scale = (4 - order) / (knots[i + 4] - knots[i + order])
    return np.stack([-scale, scale], axis=1)


def velocity_operator(n_spans: int) -> CooMatrix:
    """``K_u``: hodograph control points ``eta = K_u tau`` of ``dS/du`` (eq. 46-47 with alpha = 1).

    Rows ``[-3, 3]``, ``[-3/2, 3/2]``, ``[-1, 1]``, ... , ``[-3/2, 3/2]``, ``[-3, 3]`` for m >= 4.
    Shape ``(m + 2, m + 3)``. Multiply by ``alpha`` for the time derivative.
    """
    return _band(_difference_values(n_spans, 1), n_spans + DEGREE)


@lru_cache(maxsize=64)
def velocity_values(n_spans: int) -> FloatArray:
    """Rows of ``K_u`` (:func:`velocity_operator`) for :func:`apply_band`, shape ``(m + 2, 2)``."""
    values = _difference_values(n_spans, 1)
    values.setflags(write=False)
    return values


@lru_cache(maxsize=64)
def _acceleration_values(n_spans: int) -> FloatArray:
    """Rows of ``L_u = K'_u K_u``, shape ``(m + 1, 3)``: row ``i`` is columns ``i .. i + 2``."""
    k = _difference_values(n_spans, 1)  # K_u, (m + 2, 2)
    k2 = _difference_values(n_spans, 2)  # K'_u of eq. (50), (m + 1, 2)
    return np.stack(
        [k2[:, 0] * k[:-1, 0], k2[:, 0] * k[:-1, 1] + k2[:, 1] * k[1:, 0], k2[:, 1] * k[1:, 1]],
        axis=1,
    )


@lru_cache(maxsize=64)
def acceleration_operator(n_spans: int) -> CooMatrix:
    """``L_u = K'_u K_u`` (eq. 52 with alpha = 1), shape ``(m + 1, m + 3)``.

    Rows ``[6, -9, 3]``, ``[3/2, -5/2, 1]``, ``[1, -2, 1]``, .... The second derivative is
    piecewise linear with value ``(L_u tau)_k`` at knot ``u = k``: bounding these rows bounds
    the acceleration exactly (not only sufficiently).
    """
    return _band(_acceleration_values(n_spans), n_spans + DEGREE)


@lru_cache(maxsize=64)
def _jerk_values(n_spans: int) -> FloatArray:
    """Rows of ``D3_u``, shape ``(m, 4)``: row ``s`` is columns ``s .. s + 3``."""
    accel = _acceleration_values(n_spans)
    zero = np.zeros((n_spans, 1))
    return np.hstack([zero, accel[1:]]) - np.hstack([accel[:-1], zero])


def span_jerk_u(control_points: FloatArray) -> FloatArray:
    """``D3_u @ control_points``: the constant third derivative w.r.t. ``u`` on each span."""
    return apply_band(_jerk_values(int(control_points.shape[0]) - DEGREE), control_points)


@lru_cache(maxsize=64)
def jerk_operator(n_spans: int) -> CooMatrix:
    """``D3_u``: constant third derivative on each span, shape ``(m, m + 3)``.

    The linear hodograph has unit knot spacing, so the jerk on span ``s`` is
    ``(L_u tau)_{s+1} - (L_u tau)_s``.
    """
    return _band(_jerk_values(n_spans), n_spans + DEGREE)


_GRAM_EDGE = 8
"""Columns at each end of :func:`jerk_gram_banded` that the boundary spans reach (3 spans of
4 columns, plus margin); the columns between hold the interior value."""


@lru_cache(maxsize=64)
def jerk_gram_banded(n_spans: int) -> FloatArray:
    """Upper banded storage (LAPACK ``ab``, 3 super-diagonals) of ``G_u = D3_u^T D3_u``.

    ``G = alpha**5 * G_u`` is eq. (34): ``int (d^3 S/dt^3)^2 dt = tau^T G tau``. Each span has
    unit length in ``u``, so the integral of the squared constant jerk is the plain sum.
    Long splines are assembled from the ``4 * _GRAM_EDGE``-span one (the same sums, so the same
    numbers, bit for bit), as a spline of a new length appears at nearly every re-timing step.
    """
    reference_spans = 4 * _GRAM_EDGE
    if n_spans <= reference_spans:
        return _jerk_gram_summed(n_spans)
    reference = jerk_gram_banded(reference_spans)
    middle = n_spans + DEGREE - 2 * _GRAM_EDGE
    ab = np.concatenate(
        [
            reference[:, :_GRAM_EDGE],
            np.repeat(reference[:, _GRAM_EDGE : _GRAM_EDGE + 1], middle, axis=1),
            reference[:, -_GRAM_EDGE:],
        ],
        axis=1,
    )
    ab.setflags(write=False)
    return ab


def _jerk_gram_summed(n_spans: int) -> FloatArray:
    """:func:`jerk_gram_banded` summed span by span."""
    jerk = _jerk_values(n_spans)
    n = n_spans + DEGREE
    ab = np.zeros((4, n))
    for a in range(4):  # entry (s + a, s + b) of span s's outer product sits at ab[3 - (b - a)]
        for b in range(a, 4):
            ab[3 - (b - a), b : b + n_spans] += jerk[:, a] * jerk[:, b]
    ab.setflags(write=False)
    return ab


def jerk_gram(n_spans: int, alpha: float) -> FloatArray:
    """Dense ``G`` of eq. (34) in time units: ``alpha**5 * D3_u^T D3_u`` (for checks; the fits
    use :func:`jerk_gram_banded`)."""
    d3 = jerk_operator(n_spans).toarray()
    return np.asarray(alpha**5 * (d3.T @ d3))


# --- a spline as a value ----------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class ClampedCubicSpline:
    """A clamped uniform cubic B-spline trajectory ``p(t)``, ``t`` in [0, duration_s]."""

    control_points: FloatArray
    """Control points ``tau``, shape (n_spans + 3, d); units of the curve (e.g. [m])."""
    duration_s: float
    """Total time ``T`` in [s]; knots are ``T / n_spans`` apart in time."""

    @property
    def n_spans(self) -> int:
        """Number of unit spans ``m`` of the knot vector."""
        return int(self.control_points.shape[0]) - DEGREE

    @property
    def alpha(self) -> float:
        """Knots per second ``m / T`` in [1/s]."""
        return self.n_spans / self.duration_s

    def evaluate(self, t_s: FloatArray, derivative: int = 0) -> FloatArray:
        """The ``derivative``-th time derivative at times ``t_s`` (clamped to the interval)."""
        u = self.alpha * np.asarray(t_s, dtype=np.float64)
        rows = basis_rows(u, self.n_spans, derivative)
        return rows.apply(self.control_points) * self.alpha**derivative

    def knot_times_s(self) -> FloatArray:
        """The ``m + 1`` distinct knot times in [s]."""
        return np.linspace(0.0, self.duration_s, self.n_spans + 1)

    def acceleration_at_knots(self) -> FloatArray:
        """Exact acceleration at the knots (it is linear in between), shape (m + 1, d)."""
        accel = apply_band(_acceleration_values(self.n_spans), self.control_points)
        return accel * self.alpha**2

    def jerk_per_span(self) -> FloatArray:
        """Constant jerk on each span, shape (m, d), in units per s^3."""
        return span_jerk_u(self.control_points) * self.alpha**3

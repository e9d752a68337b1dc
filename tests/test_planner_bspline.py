"""Clamped cubic B-spline: known answers of eq. (21)-(24), (34), (45)-(52); finite differences."""

from __future__ import annotations

import numpy as np
import pytest

from planner.bspline import (
    ClampedCubicSpline,
    acceleration_operator,
    apply_band,
    basis_rows,
    cox_de_boor,
    jerk_gram,
    jerk_gram_banded,
    jerk_operator,
    knot_vector,
    span_coefficients,
    span_jerk_u,
    velocity_operator,
    velocity_values,
)


@pytest.mark.parametrize("m", [1, 2, 3, 4, 5, 6, 7, 13])
def test_partition_of_unity_and_cox_de_boor(m: int) -> None:
    u = np.linspace(0.0, m, 7 * m + 1)
    full = basis_rows(u, m).toarray()
    assert full.shape == (u.size, m + 3)
    np.testing.assert_allclose(full.sum(axis=1), 1.0, atol=1e-13)
    assert np.all(full >= -1e-14)
    knots = knot_vector(m)
    reference = np.array([[cox_de_boor(knots, j, 3, x) for j in range(m + 3)] for x in u])
    np.testing.assert_allclose(full, reference, atol=1e-13)


def test_knot_vector_is_clamped_and_uniform() -> None:
    np.testing.assert_array_equal(knot_vector(4), [0, 0, 0, 0, 1, 2, 3, 4, 4, 4, 4])


def test_boundary_bases_match_eq_22_to_24() -> None:
    """Eq. (22)-(24) as printed have two typos: N_1 on [0,1) divides by 4 (not 8) and N_2
    on [2,3) is (3-u)^3/6 (the printed formula repeats the [0,1) piece); both are forced by
    continuity at the knots and by the recursion (17)."""
    m = 10
    u = np.linspace(0.0, 2.999, 400)
    full = basis_rows(u, m).toarray()
    n0 = np.where(u < 1, (1 - u) ** 3, 0.0)
    n1 = np.where(u < 1, u * (1 - u) ** 2 + u * (4 - 3 * u) * (2 - u) / 4, 0.0)
    n1 = np.where((u >= 1) & (u < 2), -((u - 2) ** 3) / 4, n1)
    n2 = np.select(
        [u < 1, u < 2, u < 3],
        [
            u**2 * (-3 * u + 4) / 4 + u**2 * (3 - u) / 6,
            u * (u - 2) ** 2 / 4 + (3 - u) * (-2 * u**2 + 6 * u - 3) / 6,
            (3 - u) ** 3 / 6,
        ],
    )
    np.testing.assert_allclose(full[:, 0], n0, atol=1e-13)
    np.testing.assert_allclose(full[:, 1], n1, atol=1e-13)
    np.testing.assert_allclose(full[:, 2], n2, atol=1e-13)
    # eq. (25)-(27): the last three bases mirror the first three.
    mirrored = basis_rows(m - u, m).toarray()
    np.testing.assert_allclose(mirrored[:, -1:-4:-1], full[:, :3], atol=1e-13)


def test_interior_basis_is_eq_21() -> None:
    m = 12
    s = np.linspace(0.0, 3.999, 500)
    column = basis_rows(4.0 + s, m).toarray()[:, 7]  # B_3(u - 4)
    expected = np.select(
        [s < 1, s < 2, s < 3, s < 4],
        [
            s**3 / 6,
            1 / 6 - (s - 1) ** 3 / 2 + (s - 1) ** 2 / 2 + (s - 1) / 2,
            1 / 6 + (s - 3) ** 3 / 2 + (s - 3) ** 2 / 2 - (s - 3) / 2,
            -((s - 4) ** 3) / 6,
        ],
    )
    np.testing.assert_allclose(column, expected, atol=1e-13)


def test_velocity_matrix_k_pattern() -> None:
    k = velocity_operator(9).toarray()
    assert k.shape == (11, 12)
    np.testing.assert_allclose(k[0, :2], [-3, 3])
    np.testing.assert_allclose(k[1, 1:3], [-1.5, 1.5])
    np.testing.assert_allclose(k[2, 2:4], [-1, 1])
    np.testing.assert_allclose(k[5, 5:7], [-1, 1])
    np.testing.assert_allclose(k[-2, -3:-1], [-1.5, 1.5])
    np.testing.assert_allclose(k[-1, -2:], [-3, 3])
    assert np.count_nonzero(k) == 2 * 11


def test_acceleration_matrix_l_pattern() -> None:
    """Rows of eq. (52); the paper prints the last two rows unmirrored ([6,-9,3], [3/2,-5/2,1]);
    by symmetry of the clamped knots they are [3,-9,6] and [1,-5/2,3/2]."""
    ell = acceleration_operator(9).toarray()
    assert ell.shape == (10, 12)
    np.testing.assert_allclose(ell[0, :3], [6, -9, 3])
    np.testing.assert_allclose(ell[1, 1:4], [1.5, -2.5, 1])
    np.testing.assert_allclose(ell[2, 2:5], [1, -2, 1])
    np.testing.assert_allclose(ell[6, 6:9], [1, -2, 1])
    np.testing.assert_allclose(ell[-2, -4:-1], [1, -2.5, 1.5])
    np.testing.assert_allclose(ell[-1, -3:], [3, -9, 6])
    assert np.count_nonzero(ell) == 3 * 10


def _random_spline(m: int, duration: float, seed: int = 0) -> ClampedCubicSpline:
    ctrl = np.random.default_rng(seed).normal(size=(m + 3, 3))
    return ClampedCubicSpline(control_points=ctrl, duration_s=duration)


def test_derivatives_match_finite_differences() -> None:
    spline = _random_spline(11, 4.4)
    t = np.linspace(0.01, 4.39, 301)
    h = 1e-5
    for order in (1, 2, 3):
        numeric = (spline.evaluate(t + h, order - 1) - spline.evaluate(t - h, order - 1)) / (2 * h)
        analytic = spline.evaluate(t, order)
        scale = np.max(np.abs(analytic))
        if order == 3:  # jerk jumps at knots: compare away from them
            u = spline.alpha * t
            away = np.abs(u - np.round(u)) > 1e-3
            numeric, analytic = numeric[away], analytic[away]
        np.testing.assert_allclose(analytic, numeric, atol=1e-6 * scale)


def test_k_and_l_give_the_hodographs() -> None:
    """K tau and L tau are the control points of p' and p'' (alpha scaling, eq. 46, 50)."""
    spline = _random_spline(8, 3.0, seed=3)
    alpha = spline.alpha
    accel_at_knots = spline.evaluate(spline.knot_times_s(), 2)
    np.testing.assert_allclose(spline.acceleration_at_knots(), accel_at_knots, atol=1e-10)
    eta = alpha * (velocity_operator(8) @ spline.control_points)
    np.testing.assert_allclose(eta[0], spline.evaluate(np.array([0.0]), 1)[0], atol=1e-12)
    np.testing.assert_allclose(eta[-1], spline.evaluate(np.array([3.0]), 1)[0], atol=1e-12)


def test_jerk_gram_is_the_integral_of_squared_jerk() -> None:
    m, duration = 9, 2.7
    spline = _random_spline(m, duration, seed=5)
    t = (np.arange(m * 200) + 0.5) / (m * 200) * duration  # midpoint rule, exact per span
    integral = np.sum(spline.evaluate(t, 3) ** 2, axis=0) * duration / t.size
    gram = jerk_gram(m, spline.alpha)
    quad = np.einsum("ia,ij,ja->a", spline.control_points, gram, spline.control_points)
    np.testing.assert_allclose(quad, integral, rtol=1e-10)


def test_interior_jerk_gram_row() -> None:
    """Autocorrelation of the uniform cubic's jerk [1, -3, 3, -1]."""
    ab = jerk_gram_banded(14)
    np.testing.assert_allclose(ab[:, 8], [-1, 6, -15, 20])


@pytest.mark.parametrize("m", [4, 7, 32, 33, 41, 150, 487])
def test_banded_jerk_gram_is_the_dense_product(m: int) -> None:
    """Long splines' Gram (assembled from a shorter one) against ``D3^T D3`` multiplied out."""
    dense = jerk_gram(m, 1.0)
    ab = jerk_gram_banded(m)
    for k in range(4):
        np.testing.assert_allclose(ab[3 - k, k:], np.diag(dense, k), rtol=0, atol=1e-12)


@pytest.mark.parametrize("m", [4, 9, 60])
def test_band_products_are_the_operator_products_bit_for_bit(m: int) -> None:
    """The shifted-slice products sum each row's terms in the sparse product's order."""
    spline = _random_spline(m, 2.0, seed=m)
    ctrl = spline.control_points
    velocity = np.asarray(velocity_operator(m) @ ctrl)
    assert np.array_equal(apply_band(velocity_values(m), ctrl), velocity)
    assert np.array_equal(apply_band(velocity_values(m), ctrl[:, 0]), velocity[:, 0])
    assert np.array_equal(span_jerk_u(ctrl), np.asarray(jerk_operator(m) @ ctrl))
    accel = np.asarray(acceleration_operator(m) @ ctrl) * spline.alpha**2
    assert np.array_equal(spline.acceleration_at_knots(), accel)


def test_span_table_interior_is_uniform_for_large_m() -> None:
    big, small = span_coefficients(40), span_coefficients(6)
    np.testing.assert_allclose(big[:3], small[:3])
    np.testing.assert_allclose(big[-3:], small[-3:])
    np.testing.assert_allclose(big[10], big[20])

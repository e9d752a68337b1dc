"""The closed form's band solver (planner.band_solve) against numpy's dense solve."""

from __future__ import annotations

import numpy as np
import pytest

from planner.band_solve import BLOCK_SIZE, solve_symmetric_band


def _band(n: int, seed: int, definite: bool) -> tuple[np.ndarray, np.ndarray]:
    """A symmetric matrix with 3 super-diagonals: dense and in upper band storage."""
    rng = np.random.default_rng(seed)
    dense = np.zeros((n, n))
    for k in range(min(4, n)):
        values = rng.normal(size=n - k)
        dense += np.diag(values, k) + (np.diag(values, -k) if k else 0.0)
    if definite:
        dense += 8.0 * np.eye(n)  # diagonally dominant: positive definite
    upper = np.zeros((4, n))
    for k in range(min(4, n)):
        upper[3 - k, k:] = np.diag(dense, k)
    return dense, upper


SIZES = [1, 2, 4, BLOCK_SIZE - 1, BLOCK_SIZE, BLOCK_SIZE + 1, 2 * BLOCK_SIZE + 3, 7 * BLOCK_SIZE]


@pytest.mark.parametrize("n", SIZES)
@pytest.mark.parametrize("definite", [True, False])
def test_band_solve_equals_the_dense_solve(n: int, definite: bool) -> None:
    """Positive definite, and indefinite (where a Cholesky factorisation would stop), across the
    block boundaries; several right-hand sides and one."""
    dense, upper = _band(n, seed=n, definite=definite)
    rhs = np.random.default_rng(1).normal(size=(n, 3))
    expected = np.linalg.solve(dense, rhs)
    scale = np.max(np.abs(expected))
    np.testing.assert_allclose(solve_symmetric_band(upper, rhs), expected, atol=1e-10 * scale)
    one = solve_symmetric_band(upper, rhs[:, 0])
    assert one.shape == (n,)
    np.testing.assert_allclose(one, expected[:, 0], atol=1e-10 * scale)


def test_band_solve_ignores_the_unused_corner_of_the_storage() -> None:
    """Like LAPACK, entries above the first super-diagonals' start are not read."""
    dense, upper = _band(60, seed=3, definite=True)
    upper[0, :3] = upper[1, :2] = upper[2, :1] = np.nan
    rhs = np.ones(60)
    np.testing.assert_allclose(solve_symmetric_band(upper, rhs), np.linalg.solve(dense, rhs))

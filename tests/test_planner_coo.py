"""Coordinate-form sparse matrices (planner.coo) against their dense numpy equivalents."""

from __future__ import annotations

import numpy as np

from planner.coo import CooMatrix, kron, vstack


def _random(shape: tuple[int, int], seed: int) -> CooMatrix:
    rng = np.random.default_rng(seed)
    dense = rng.normal(size=shape) * (rng.uniform(size=shape) < 0.3)
    rows, cols = np.nonzero(dense)
    return CooMatrix(rows, cols, dense[rows, cols], shape)


def test_products_rows_and_stacks_equal_the_dense_ones() -> None:
    a, b = _random((7, 5), seed=1), _random((4, 5), seed=2)
    x = np.random.default_rng(3).normal(size=(5, 3))
    np.testing.assert_allclose(a @ x, a.toarray() @ x, atol=1e-14)
    np.testing.assert_allclose(a @ x[:, 0], a.toarray() @ x[:, 0], atol=1e-14)
    rows = np.array([1, 4, 6])
    np.testing.assert_array_equal(a.take_rows(rows).toarray(), a.toarray()[rows])
    np.testing.assert_array_equal(vstack([a, b]).toarray(), np.vstack([a.toarray(), b.toarray()]))


def test_kron_equals_numpy_kron_and_keeps_row_major_order() -> None:
    left = np.array([[1.0, 0.0, -2.0], [0.0, 0.5, 0.0]])
    right = _random((4, 6), seed=4)
    product = kron(left, right)
    np.testing.assert_array_equal(product.toarray(), np.kron(left, right.toarray()))
    np.testing.assert_array_equal(
        np.lexsort((product.cols, product.rows)), np.arange(product.rows.size)
    )
    assert np.count_nonzero(product.values == 0.0) == 0  # zeros of ``left`` are left out

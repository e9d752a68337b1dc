"""Sparse matrices as their non-zero entries (coordinate form) in plain numpy.

The planner's difference operators and its QP matrices are built as :class:`CooMatrix`, so a plan
needs SciPy only where a sparse solver takes the matrix (``planner.qp_solvers`` converts there):
importing ``scipy.sparse`` costs a one-off command about 0.2 s, more than the plan itself.
Entries are kept in row-major order (rows ascending, columns ascending within a row), as CSR
keeps them, so a product sums each row's terms in the order a CSR product does.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True, eq=False)
class CooMatrix:
    """A sparse matrix: ``values[k]`` at ``(rows[k], cols[k])``, no two entries at one place."""

    rows: NDArray[np.int64]
    """Row of each entry, shape (nnz,)."""
    cols: NDArray[np.int64]
    """Column of each entry, shape (nnz,)."""
    values: NDArray[np.float64]
    """Value of each entry, shape (nnz,); an explicit zero stays an entry."""
    shape: tuple[int, int]
    """Rows and columns of the whole matrix."""

    def __matmul__(self, x: NDArray[np.float64]) -> NDArray[np.float64]:
        """The product with a vector (n,) or a matrix (n, d)."""
        x = np.asarray(x, dtype=np.float64)
        if x.ndim == 1:
            return _row_sums(self.rows, self.values * x[self.cols], self.shape[0])
        terms = self.values[:, None] * x[self.cols]
        columns = [_row_sums(self.rows, terms[:, k], self.shape[0]) for k in range(x.shape[1])]
        return np.stack(columns, axis=1) if columns else np.zeros((self.shape[0], 0))

    def toarray(self) -> NDArray[np.float64]:
        """The dense matrix."""
        dense = np.zeros(self.shape)
        dense[self.rows, self.cols] = self.values
        return dense

    def take_rows(self, rows: NDArray[np.int64]) -> CooMatrix:
        """The matrix of rows ``rows`` (ascending, distinct), numbered 0 .. len(rows) - 1."""
        keep = np.isin(self.rows, rows)
        new_rows = np.searchsorted(rows, self.rows[keep])
        return CooMatrix(new_rows, self.cols[keep], self.values[keep], (len(rows), self.shape[1]))


def _row_sums(
    rows: NDArray[np.int64], terms: NDArray[np.float64], n_rows: int
) -> NDArray[np.float64]:
    return np.bincount(rows, weights=terms, minlength=n_rows).astype(np.float64)


def _row_major(
    rows: NDArray[np.int64],
    cols: NDArray[np.int64],
    values: NDArray[np.float64],
    shape: tuple[int, int],
) -> CooMatrix:
    """A :class:`CooMatrix` of these entries, sorted into row-major order (one sort on the flat
    index ``row * n_cols + col``, unique per entry: half the time of a two-key ``lexsort``)."""
    order = np.argsort(rows * shape[1] + cols, kind="stable")
    return CooMatrix(rows[order], cols[order], values[order], shape)


def kron(left: NDArray[np.float64], right: CooMatrix) -> CooMatrix:
    """The Kronecker product of a small dense matrix and a sparse one (zeros of ``left`` left
    out): block ``(i, j)`` is ``left[i, j] * right``."""
    i, j = np.nonzero(left)
    n_rows, n_cols = right.shape
    rows = (i[:, None] * n_rows + right.rows[None, :]).ravel()
    cols = (j[:, None] * n_cols + right.cols[None, :]).ravel()
    values = (left[i, j][:, None] * right.values[None, :]).ravel()
    shape = (left.shape[0] * n_rows, left.shape[1] * n_cols)
    return _row_major(rows, cols, values, shape)


def vstack(blocks: Sequence[CooMatrix]) -> CooMatrix:
    """The matrices one below the other (they have the same number of columns)."""
    offsets = np.cumsum([0] + [b.shape[0] for b in blocks])
    return CooMatrix(
        np.concatenate([b.rows + offset for b, offset in zip(blocks, offsets, strict=False)]),
        np.concatenate([b.cols for b in blocks]),
        np.concatenate([b.values for b in blocks]),
        (int(offsets[-1]), blocks[0].shape[1]),
    )

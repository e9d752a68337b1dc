"""Symmetric band systems ``A x = rhs``: the closed-form fit's normal equations.

LAPACK's ``dgbsv`` from numpy's own OpenBLAS solves them where numpy's wheels bundle it
(planner.lapack_band); elsewhere :func:`solve_symmetric_band_blocks` solves them in plain numpy.

``A`` is given in LAPACK's upper band storage (``ab[u + i - j, j] == A[i, j]`` for ``i <= j``),
as :func:`scipy.linalg.solveh_banded` takes it; importing ``scipy.linalg`` would cost a one-off
``skyquill plan`` about 0.3 s, several times the plan. The band is cut into dense blocks of
``BLOCK_SIZE`` rows, so that ``A`` is block tridiagonal, and solved by block LU (the block Thomas
algorithm): one dense solve (LU with partial pivoting) per block, so the loop in Python runs
``n / BLOCK_SIZE`` times. Pivoting within each block also solves the normal matrices that
round-off made slightly indefinite, where a Cholesky factorisation would stop.

Measured against ``solveh_banded`` (3 super-diagonals, 3 right-hand sides, one core at load
1.5): 0.16 against 0.03 ms at n = 88 (a character of 18 s), 0.3-0.5 against 0.08 ms at n = 336
(the longest characters), 7-11 against 0.8-1.1 ms at n = 5750 (64 characters); the solutions
agree to 1e-12 relative. A plan makes 10-14 of these solves.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from planner.lapack_band import band_solver

BLOCK_SIZE = 48
"""Rows per dense block (fewer when the band has fewer rows); 48 was the fastest of 8 to 96 for
bands of 88 to 5750 rows."""


@lru_cache(maxsize=4)
def _block_pattern(bandwidth: int, b: int) -> tuple[NDArray[np.int64], ...]:
    """Where the band sits in a block of ``b`` rows (the same in every block): for each entry of
    the diagonal block its band row and its row and column in the block; then for each entry
    crossing into the next block its band row, its row in this block and column in the next."""
    band_k, rows, cols = [], [], []
    for k in range(min(bandwidth, b - 1) + 1):  # entry (i, i + k) is ab[bandwidth - k, i + k]
        r = np.arange(b - k)
        band_k.append(np.full(b - k, bandwidth - k))
        rows.append(r)
        cols.append(r + k)
    across_k = [np.full(k, bandwidth - k) for k in range(1, min(bandwidth, b) + 1)]
    across_c = [np.arange(k) for k in range(1, min(bandwidth, b) + 1)]
    across_r = [b - k + c for k, c in zip(range(1, min(bandwidth, b) + 1), across_c, strict=True)]
    return tuple(
        np.concatenate(parts).astype(np.int64) if parts else np.zeros(0, dtype=np.int64)
        for parts in (band_k, rows, cols, across_k, across_r, across_c)
    )


def _blocks(
    ab_upper: NDArray[np.float64], b: int
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The diagonal blocks (n_blocks, b, b) of ``b`` rows (the last one padded with the
    identity) and the super-diagonal blocks (the band crossing from one block into the next):
    the band cut into blocks of ``b`` columns, each scattered by the same pattern."""
    bandwidth, n = ab_upper.shape[0] - 1, ab_upper.shape[1]
    n_blocks = -(-n // b)
    padded = np.zeros((bandwidth + 1, n_blocks * b))
    padded[:, :n] = ab_upper
    padded[bandwidth, n:] = 1.0
    bands = padded.reshape(bandwidth + 1, n_blocks, b).transpose(1, 0, 2)
    band_k, rows, cols, across_k, across_r, across_c = _block_pattern(bandwidth, b)
    diagonal = np.zeros((n_blocks, b, b))
    values = bands[:, band_k, cols]
    diagonal[:, cols, rows] = values
    diagonal[:, rows, cols] = values
    upper = np.zeros((n_blocks, b, b))
    upper[:-1, across_r, across_c] = bands[1:, across_k, across_c]
    return diagonal, upper


def solve_symmetric_band(
    ab_upper: NDArray[np.float64], rhs: NDArray[np.float64]
) -> NDArray[np.float64]:
    """``x`` with ``A x = rhs`` for symmetric ``A`` in upper band storage ``ab_upper`` (u + 1, n);
    ``rhs`` (n,) or (n, d). Raises ``numpy.linalg.LinAlgError`` where ``A`` is singular."""
    lapack = band_solver()
    if lapack is not None:
        return lapack(ab_upper, rhs)
    return solve_symmetric_band_blocks(ab_upper, rhs)


def solve_symmetric_band_blocks(
    ab_upper: NDArray[np.float64], rhs: NDArray[np.float64]
) -> NDArray[np.float64]:
    """:func:`solve_symmetric_band` in plain numpy, by block LU (see the module docstring).
    Raises ``numpy.linalg.LinAlgError`` where a block is singular."""
    bandwidth, n = ab_upper.shape[0] - 1, ab_upper.shape[1]
    b = min(BLOCK_SIZE, n)
    diagonal, upper = _blocks(ab_upper, b)
    n_blocks = diagonal.shape[0]
    columns = rhs.reshape(n, -1)
    d = columns.shape[1]
    # Block row i: diagonal[i] x_i + upper[i] x_{i+1} + upper[i - 1]^T x_{i-1} = rhs_i, where
    # upper[i] is zero but for its last u rows and first u columns (the band crossing blocks).
    # work[i] holds [upper[i][:, :u] | rhs_i], then its solve by the Schur complement of block i.
    u = min(bandwidth, b)
    work = np.zeros((n_blocks, b, u + d))
    work[:, :, :u] = upper[:, :, :u]
    work.reshape(n_blocks * b, u + d)[:n, u:] = columns
    for i in range(n_blocks):
        schur = diagonal[i]
        if i:
            update = upper[i - 1, b - u :, :u].T @ work[i - 1, b - u :]
            schur = schur.copy()
            schur[:u, :u] -= update[:, :u]
            work[i, :u, u:] -= update[:, u:]
        work[i] = np.linalg.solve(schur, work[i])
    x = np.empty((n_blocks, b, d))
    x[-1] = work[-1, :, u:]
    for i in range(n_blocks - 2, -1, -1):
        x[i] = work[i, :, u:] - work[i, :, :u] @ x[i + 1, :u]
    return x.reshape(n_blocks * b, d)[:n].reshape(rhs.shape)

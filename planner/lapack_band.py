"""LAPACK's band solver ``dgbsv`` from the library numpy already loaded: no SciPy import.

numpy's wheels link their linear algebra against ``scipy-openblas`` (OpenBLAS with all of LAPACK,
64-bit integers, symbols prefixed ``scipy_`` and suffixed ``64_``), bundled beside the package
(``numpy.libs`` on Linux and Windows, ``numpy/.dylibs`` on macOS). numpy itself exposes no band
solver, and ``scipy.linalg.solveh_banded`` would cost a one-off ``skyquill plan`` about 0.3 s of
import; the library is already in memory, so opening it with ctypes (loaded by numpy) costs
nothing. ``dgbsv`` is LU with partial pivoting on the band: it also solves the normal matrices
that round-off made slightly indefinite, where a Cholesky factorisation (``dpbsv``) would stop.

:func:`band_solver` is ``None`` where numpy was built against another LAPACK (a distribution's
or conda's numpy); planner.band_solve then solves in plain numpy. Measured (3 right-hand sides,
one core, load ~2): 0.017 against 0.051 ms for the plain-numpy block solve at 48 rows, 0.06
against 0.30 ms at 162 (a Chinese character), 1.7 against 17 ms at 5750; equal to 1e-15.
"""

from __future__ import annotations

import ctypes
import os
from collections.abc import Callable
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

COL_MAJOR = 102
"""LAPACKE's ``LAPACK_COL_MAJOR``."""
SYMBOL = "scipy_LAPACKE_dgbsv64_"
"""``LAPACKE_dgbsv`` in scipy-openblas (64-bit integers)."""

BandSolver = Callable[[NDArray[np.float64], NDArray[np.float64]], NDArray[np.float64]]


def _library_paths() -> list[str]:
    """Where numpy's wheels put their bundled OpenBLAS (listed without ``glob``, which a
    one-off ``skyquill plan`` would import for this alone)."""
    here = os.path.dirname(np.__file__)
    folders = [os.path.join(os.path.dirname(here), "numpy.libs"), os.path.join(here, ".dylibs")]
    found = []
    for folder in folders:
        try:
            names = os.listdir(folder)
        except OSError:
            continue
        found += [os.path.join(folder, name) for name in names if "scipy_openblas" in name]
    return sorted(found)


@lru_cache(maxsize=1)
def band_solver() -> BandSolver | None:
    """``solve(ab_upper, rhs)`` by LAPACK ``dgbsv`` (see :func:`solve_with`), or ``None`` when
    numpy's LAPACK is not scipy-openblas."""
    for path in _library_paths():
        try:
            function = getattr(ctypes.CDLL(path), SYMBOL)
        except (OSError, AttributeError):
            continue
        i64, ptr = ctypes.c_int64, ctypes.c_void_p
        function.argtypes = [ctypes.c_int, i64, i64, i64, i64, ptr, i64, ptr, ptr, i64]
        function.restype = i64
        return lambda ab_upper, rhs: solve_with(function, ab_upper, rhs)
    return None


def solve_with(
    dgbsv: Callable[..., int], ab_upper: NDArray[np.float64], rhs: NDArray[np.float64]
) -> NDArray[np.float64]:
    """``x`` with ``A x = rhs`` for symmetric ``A`` in upper band storage ``ab_upper`` (u + 1, n)
    (``ab[u + i - j, j] == A[i, j]``, ``i <= j``); ``rhs`` (n,) or (n, d). Raises
    ``numpy.linalg.LinAlgError`` when ``A`` is singular."""
    u, n = ab_upper.shape[0] - 1, ab_upper.shape[1]
    # General band storage, column major: AB(2u + i - j, j) = A(i, j) for |i - j| <= u, with u
    # rows of room for the fill-in of the pivoting on top. Row j of ``band`` is column j.
    band = np.zeros((n, 3 * u + 1))
    for k in range(min(u, n - 1) + 1):  # A(j - k, j) = A(j, j - k) = ab_upper[u - k, j]
        band[k:, 2 * u - k] = ab_upper[u - k, k:]
        band[: n - k, 2 * u + k] = ab_upper[u - k, k:]
    columns = np.array(rhs.reshape(n, -1).T, dtype=np.float64, order="C")  # (d, n): column major
    pivots = np.empty(n, dtype=np.int64)
    info = dgbsv(
        COL_MAJOR, n, u, u, columns.shape[0], band.ctypes.data, 3 * u + 1,
        pivots.ctypes.data, columns.ctypes.data, n,
    )  # fmt: skip
    if info != 0:
        raise np.linalg.LinAlgError(f"dgbsv: info {info} (singular band matrix)")
    return np.asarray(columns.T.reshape(rhs.shape))

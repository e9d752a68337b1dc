"""The planner's caches hold what a plan reuses, not every size a long-lived planning worker
once planned (issue 35: a kept worker holds only what it reuses)."""

from __future__ import annotations

import gc
import tracemalloc

import numpy as np

from planner.qp_structure import STRUCTURES_KEPT, structure

MIB = 1024.0 * 1024.0


def test_qp_structures_of_many_sizes_are_not_all_kept() -> None:
    """A show's characters are planned at sizes of their own (36-225 spans for the Airshow's
    corpus). Keeping the 32 latest sizes held 14.4 MiB in a worker after 300 distinct
    characters; 40 sizes near 200 spans left 13.8 MiB held here."""
    sizes = range(180, 220)
    for n_spans in sizes:  # the B-spline operators' own caches (64 sizes) filled beforehand
        structure(n_spans, True)
    structure.cache_clear()
    gc.collect()
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        for n_spans in sizes:
            built = structure(n_spans, True)
            assert built.G.shape == (3 * (n_spans + 1) + 13 * (n_spans + 2), 3 * (n_spans + 3))
        del built
        gc.collect()
        held_mib = (tracemalloc.get_traced_memory()[0] - before) / MIB
    finally:
        tracemalloc.stop()
        structure.cache_clear()
    one_structure_mib = 2.2 * 220 / 1024.0  # 2.1 KiB per span, measured
    assert held_mib <= STRUCTURES_KEPT * one_structure_mib + 0.1, held_mib
    assert STRUCTURES_KEPT * one_structure_mib < 2.0  # kept 32 sizes: 13.8 MiB


def test_a_structure_reused_is_the_same_as_one_built_afresh() -> None:
    """What a re-fit at the same size reuses is exactly what it would have built."""
    structure.cache_clear()
    first = structure(150, True)
    assert structure(150, True) is first  # the re-fit of a plan hits
    for n_spans in range(151, 151 + 2 * STRUCTURES_KEPT):
        structure(n_spans, True)
    again = structure(150, True)
    assert again is not first  # long evicted: built afresh, equal
    np.testing.assert_array_equal(again.G.rows, first.G.rows)
    np.testing.assert_array_equal(again.G.cols, first.G.cols)
    np.testing.assert_array_equal(again.G.values, first.G.values)
    np.testing.assert_array_equal(again.P_gather, first.P_gather)
    structure.cache_clear()

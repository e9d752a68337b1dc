"""Split-and-merge turning points (section 4)."""

from __future__ import annotations

import itertools

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.turning_points import split_and_merge


def test_l_shape_gives_three_points() -> None:
    down = np.c_[np.zeros(20), np.linspace(1.0, 0.0, 20)]
    right = np.c_[np.linspace(0.0, 0.6, 15), np.zeros(15)][1:]
    pts = np.vstack([down, right])
    idx = split_and_merge(pts, 0.01)
    np.testing.assert_array_equal(idx, [0, 19, pts.shape[0] - 1])


def test_straight_line_gives_two_points() -> None:
    x = np.linspace(0.0, 1.0, 50)
    noise = 0.002 * np.sin(37 * x)
    np.testing.assert_array_equal(split_and_merge(np.c_[x, 2 * x + noise], 0.01), [0, 49])


def test_zigzag_keeps_every_corner_in_order() -> None:
    corners = np.array([[0, 0], [1, 1], [2, 0], [3, 1], [4, 0]], dtype=float)
    pts = np.vstack(
        [np.linspace(a, b, 10, endpoint=False) for a, b in itertools.pairwise(corners)]
        + [corners[-1:]]
    )
    idx = split_and_merge(pts, 0.05)
    np.testing.assert_allclose(pts[idx], corners)


def test_closed_loop_keeps_far_points() -> None:
    th = np.linspace(0.0, 2 * np.pi, 60)
    idx = split_and_merge(np.c_[np.cos(th), np.sin(th)], 0.05)
    assert idx[0] == 0 and idx[-1] == 59
    assert len(idx) >= 8


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.tuples(st.floats(-1, 1), st.floats(-1, 1)), min_size=2, max_size=40),
    st.floats(0.005, 0.3),
)
def test_every_point_within_threshold_of_the_polyline(
    raw: list[tuple[float, float]], threshold: float
) -> None:
    pts = np.array(raw)
    idx = split_and_merge(pts, threshold)
    assert idx[0] == 0 and idx[-1] == len(pts) - 1
    assert np.all(np.diff(idx) > 0)
    for a, b in itertools.pairwise(idx):
        assert _max_distance(pts, a, b) <= threshold + 1e-12
    # merged: no turning point could be dropped while keeping its neighbours' points in reach
    for k in range(1, len(idx) - 1):
        assert _max_distance(pts, idx[k - 1], idx[k + 1]) > threshold


def _max_distance(pts: np.ndarray, a: int, b: int) -> float:
    seg = pts[b] - pts[a]
    inner = pts[a : b + 1]
    length_sq = float(seg @ seg)
    s = np.clip((inner - pts[a]) @ seg / length_sq, 0, 1) if length_sq else np.zeros(len(inner))
    return float(np.max(np.linalg.norm(inner - (pts[a] + s[:, None] * seg), axis=1)))

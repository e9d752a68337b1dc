"""The reference a writing vehicle is given each tick: the plan's samples interpolated at agent
time, checked against numpy's own linear interpolation."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.samples import TrajectorySamples
from vehicle_agent.reference_track import ReferenceTrack


@st.composite
def plans(draw: st.DrawFn) -> tuple[TrajectorySamples, np.ndarray]:
    n = draw(st.integers(2, 40))
    steps = draw(st.lists(st.floats(1e-3, 0.5), min_size=n, max_size=n))
    t = np.cumsum(steps) - steps[0] + draw(st.floats(-2.0, 2.0))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    columns = [rng.normal(size=(n, 3)) for _ in range(3)]
    pen = rng.random(n) < 0.5
    return TrajectorySamples(t, *columns, pen), rng.uniform(0.5, 6.0, n)


@settings(max_examples=200, deadline=None)
@given(plans(), st.lists(st.floats(-5.0, 30.0), min_size=1, max_size=20))
def test_the_reference_is_the_plan_interpolated_and_clamped(
    plan: tuple[TrajectorySamples, np.ndarray], times_s: list[float]
) -> None:
    samples, force = plan
    track = ReferenceTrack(samples, force)
    t = samples.t_s
    for t_s in times_s:
        got = track.at(t_s)
        for name, values in (
            ("position_m_enu", samples.position_m_enu),
            ("velocity_mps_enu", samples.velocity_mps_enu),
            ("acceleration_mps2_enu", samples.acceleration_mps2_enu),
        ):
            want = [np.interp(t_s, t, values[:, k]) for k in range(3)]
            np.testing.assert_allclose(getattr(got, name), want, rtol=1e-12, atol=1e-12)
        assert track.motion_at(t_s) == (
            got.position_m_enu,
            got.velocity_mps_enu,
            got.acceleration_mps2_enu,
        )
        assert got.force_n is not None
        np.testing.assert_allclose(got.force_n, np.interp(t_s, t, force), rtol=1e-12)
        nearest = int(np.argmin(np.abs(t - t_s)))  # the pen is the nearest sample's
        distances = np.sort(np.abs(t - t_s))
        if distances[1] - distances[0] > 1e-9:
            assert got.pen_down == bool(samples.pen_down[nearest])


def test_a_track_without_forces_gives_none_and_keeps_the_plans_arrays() -> None:
    t = np.array([0.0, 1.0])
    p = np.array([[0.0, 0.0, 1.0], [1.0, 2.0, 3.0]])
    samples = TrajectorySamples(t, p, np.zeros((2, 3)), np.zeros((2, 3)), np.array([True, True]))
    got = ReferenceTrack(samples).at(0.25)
    assert got.force_n is None and got.pen_down
    assert got.position_m_enu == (0.25, 0.5, 1.5)

"""The deviation monitor alone: above the bound for longer than the window trips, once."""

from __future__ import annotations

import math

import pytest

from vehicle_agent.safety import DeviationLimit, DeviationMonitor

DT = 0.01


def feed(monitor: DeviationMonitor, errors: list[float], t0: float = 0.0) -> float | None:
    """Feed errors one period apart; the time of the trip, or None."""
    for k, error in enumerate(errors):
        if monitor.update(error, t0 + k * DT) is not None:
            return t0 + k * DT
    return None


def test_a_short_excursion_above_the_bound_does_not_trip() -> None:
    monitor = DeviationMonitor(DeviationLimit(bound_m=0.15, window_s=0.3))
    spikes = ([0.5] * 29 + [0.01]) * 10  # 0.28 s above, then back under, again and again
    assert feed(monitor, spikes) is None and monitor.trip is None


def test_a_sustained_excursion_trips_after_the_window_and_stays_tripped() -> None:
    monitor = DeviationMonitor(DeviationLimit(bound_m=0.15, window_s=0.3))
    errors = [0.01] * 100 + [0.2 + 0.01 * k for k in range(100)]
    tripped_at = feed(monitor, errors)
    assert tripped_at == pytest.approx(1.0 + 0.3)
    trip = monitor.trip
    assert trip is not None and trip.above_since_s == pytest.approx(1.0)
    assert (
        trip.peak_m == pytest.approx(0.2 + 0.01 * 30) and "above the bound 0.150 m" in trip.message
    )
    assert monitor.update(0.0, 5.0) is trip  # latched until reset
    monitor.reset()
    assert monitor.update(0.0, 5.0) is None


def test_nan_counts_as_above_the_bound() -> None:
    monitor = DeviationMonitor(DeviationLimit(bound_m=0.15, window_s=0.0))
    trip = monitor.update(math.nan, 0.0)
    assert trip is not None and math.isinf(trip.peak_m)


@pytest.mark.parametrize(("bound", "window"), [(0.0, 0.3), (-1.0, 0.3), (0.1, -0.1)])
def test_a_limit_that_cannot_work_is_refused(bound: float, window: float) -> None:
    with pytest.raises(ValueError, match="deviation bound"):
        DeviationLimit(bound, window)

"""Typed parameters every simulated world shares: wind and motion capture (SI units, ENU)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from sim.errors import SimError

Vec3 = tuple[float, float, float]


def positive(name: str, value: float) -> None:
    """Raise :class:`SimError` naming ``name`` unless ``value`` is finite and > 0."""
    if not (value > 0.0 and math.isfinite(value)):
        raise SimError(f"must be a positive finite number, got {value!r}", field=name)


def non_negative(name: str, value: float) -> None:
    """Raise :class:`SimError` naming ``name`` unless ``value`` is finite and >= 0."""
    if not (value >= 0.0 and math.isfinite(value)):
        raise SimError(f"must be a non-negative finite number, got {value!r}", field=name)


@dataclass(frozen=True)
class WindParams:
    """Steady wind plus Ornstein-Uhlenbeck gusts per world axis (seeded per vehicle)."""

    mean_mps_enu: Vec3 = (0.0, 0.0, 0.0)
    """Steady wind velocity in [m/s], world ENU."""
    gust_sigma_mps_enu: Vec3 = (0.0, 0.0, 0.0)
    """Standard deviation of the gust velocity per axis in [m/s]."""
    gust_time_constant_s: float = 1.0
    """Correlation time of the gusts in [s]."""

    def __post_init__(self) -> None:
        positive("gust_time_constant_s", self.gust_time_constant_s)
        for value in self.gust_sigma_mps_enu:
            non_negative("gust_sigma_mps_enu", value)

    @classmethod
    def from_speed(
        cls,
        speed_mps: float,
        *,
        heading_rad: float = 0.0,
        gust_ratio: float = 0.2,
        length_scale_m: float = 8.0,
    ) -> WindParams:
        """Steady horizontal wind of ``speed_mps`` [m/s] blowing towards ``heading_rad`` (from
        east, counter-clockwise) with gusts shaped like the Dryden model at low altitude.

        Dryden (MIL-F-8785C) near the ground, about 1 m up: horizontal intensity about 0.2 of the
        wind speed, vertical half of it, length scale about 8 m; frozen turbulence carried past
        at the mean speed gives a first-order (Ornstein-Uhlenbeck) gust with time constant
        ``length_scale / speed`` (at least 0.5 s).
        """
        non_negative("speed_mps", speed_mps)
        positive("length_scale_m", length_scale_m)
        sigma = gust_ratio * speed_mps
        return cls(
            mean_mps_enu=(
                speed_mps * math.cos(heading_rad),
                speed_mps * math.sin(heading_rad),
                0.0,
            ),
            gust_sigma_mps_enu=(sigma, sigma, 0.5 * sigma),
            gust_time_constant_s=max(0.5, length_scale_m / max(speed_mps, 1e-9)),
        )


@dataclass(frozen=True)
class MocapParams:
    """Motion capture: one position frame per control tick, delayed and noisy."""

    latency_s: float = 0.005
    """Age of a frame when it reaches the controller in [s] (rounded to the physics step)."""
    noise_std_m: float = 0.0002
    """Standard deviation of the position noise per axis in [m]."""

    def __post_init__(self) -> None:
        non_negative("latency_s", self.latency_s)
        non_negative("noise_std_m", self.noise_std_m)

"""Studies over climb runs (``climb``): the same step over several seeds, and the highest step a
method climbs. What ``benchmarks/bench_ground.py`` prints and the tests check."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vehicles.omni_wheel.climb import ClimbResult, Method, climb
from vehicles.omni_wheel.geometry import OmniGeometry


@dataclass(frozen=True)
class SeededClimbs:
    """One method over one step, one run per seed."""

    runs: tuple[ClimbResult, ...]
    """The runs, in seed order."""

    @property
    def climbed(self) -> int:
        """How many runs climbed the step."""
        return sum(r.climbed for r in self.runs)

    def mean(self, figure: str) -> float:
        """Mean over the runs of the per-run average (over the wheel groups, as the paper's
        Table 2) of ``figure``: ``slip`` or ``rotation_error``."""
        per_run = [
            r.by_group(r.slip_per_wheel if figure == "slip" else r.rotation_error_per_wheel)
            for r in self.runs
        ]
        return float(np.mean([p["average"] for p in per_run]))


def seeded_climbs(
    method: Method, step_height_m: float, geometry: OmniGeometry, seeds: range
) -> SeededClimbs:
    """``method`` over a step of ``step_height_m`` [m], once per seed (sensor noise)."""
    return SeededClimbs(
        tuple(climb(method, step_height_m, geometry=geometry, seed=s) for s in seeds)
    )


def highest_step_m(
    method: Method,
    geometry: OmniGeometry,
    *,
    lo_m: float = 0.04,
    hi_m: float = 0.20,
    tol_m: float = 0.005,
) -> float:
    """Highest step in [m] ``method`` climbs, by bisection between ``lo_m`` and ``hi_m`` to
    ``tol_m`` (climbing is taken as monotonic in the height); 0 when not even ``lo_m`` is
    climbed."""
    if not climb(method, lo_m, geometry=geometry).climbed:
        return 0.0
    while hi_m - lo_m > tol_m:
        mid = 0.5 * (lo_m + hi_m)
        if climb(method, mid, geometry=geometry).climbed:
            lo_m = mid
        else:
            hi_m = mid
    return lo_m

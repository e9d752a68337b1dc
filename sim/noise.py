"""Seeded random streams per vehicle, drawn in blocks for speed.

Vehicle ``i`` of a world seeded with ``seed`` draws stream ``k`` from
``SeedSequence(seed, spawn_key=(i, k))``: its noise does not depend on how many vehicles fly with
it, and the same seed gives the same numbers bit for bit.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

WIND_STREAM = 0
"""Stream index of the gust noise."""
MOCAP_STREAM = 1
"""Stream index of the motion-capture noise."""


class NormalBlocks:
    """Standard normal draws of shape (N, 3) per call, generated ``block`` ticks at a time."""

    def __init__(self, seed: int, n_vehicles: int, stream: int, block: int = 100) -> None:
        self._generators = [
            np.random.Generator(
                np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(i, stream)))
            )
            for i in range(n_vehicles)
        ]
        self._block = block
        self._buffer: FloatArray = np.empty((0, n_vehicles, 3))
        self._next = 0

    def draw(self) -> FloatArray:
        """The next (N, 3) array of independent standard normal numbers."""
        if self._next >= self._buffer.shape[0]:
            per_vehicle = [g.standard_normal((self._block, 3)) for g in self._generators]
            self._buffer = np.stack(per_vehicle, axis=1)
            self._next = 0
        out: FloatArray = self._buffer[self._next]
        self._next += 1
        return out

"""Seeded random streams per vehicle, drawn in blocks for speed.

Vehicle ``i`` of a world seeded with ``seed`` draws stream ``k`` from
``SeedSequence(seed, spawn_key=(i, k))``: its noise does not depend on how many vehicles fly with
it, and the same seed gives the same numbers bit for bit. Vehicles taken out of a stream set
(:meth:`NormalBlocks.take`) or put together (:meth:`NormalBlocks.stack`, a fleet host's vehicles
stepped together) keep drawing the numbers they would have drawn alone.
"""

from __future__ import annotations

import copy
from collections.abc import Sequence

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

    def take(self, rows: Sequence[int]) -> NormalBlocks:
        """The streams of vehicles ``rows`` (in that order), each where it stands."""
        out = copy.copy(self)
        out._generators = [self._generators[i] for i in rows]
        out._buffer = self._buffer[:, list(rows)]
        return out

    @classmethod
    def stack(cls, parts: Sequence[NormalBlocks]) -> NormalBlocks:
        """The streams of ``parts`` side by side, each where it stands: the parts' undrawn
        blocks are brought to one length by drawing ahead (a stream of normal numbers is the
        same drawn in one call or several)."""
        left = [p._buffer[p._next :] for p in parts]
        length = max(chunk.shape[0] for chunk in left)
        columns = []
        for part, chunk in zip(parts, left, strict=True):
            short = length - chunk.shape[0]
            if short > 0:
                ahead = [g.standard_normal((short, 3)) for g in part._generators]
                chunk = np.concatenate([chunk, np.stack(ahead, axis=1)], axis=0)
            columns.append(chunk)
        out = copy.copy(parts[0])
        out._generators = [g for p in parts for g in p._generators]
        out._buffer = np.concatenate(columns, axis=1)
        out._next = 0
        return out

"""The floor a ground writer drives on: flat at z = 0 with steps across x (plain dataclasses, light:
read by the show file's route check as well as by the MuJoCo model, ``vehicles.omni_wheel.model``).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Step:
    """A step across the direction of travel: the floor is ``height_m`` high from ``x_m`` on."""

    x_m: float
    """World x in [m] of the step edge."""
    height_m: float
    """Height in [m] of the floor beyond the edge (until the next step)."""


@dataclass(frozen=True)
class Terrain:
    """Flat floor at z = 0 with steps across x (none: flat)."""

    steps: tuple[Step, ...] = ()
    """Steps in increasing x."""
    half_width_m: float = 20.0
    """Half width in [m] of the steps along y."""
    length_m: float = 40.0
    """Length in [m] of the last raised part along x."""

    def height_at_m(self, x_m: float) -> float:
        """Floor height in [m] at world x."""
        h = 0.0
        for step in self.steps:
            if x_m >= step.x_m:
                h = step.height_m
        return h

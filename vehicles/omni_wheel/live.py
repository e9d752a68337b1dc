"""The ground writer as a live simulated vehicle for the agent's ``sim`` backend.

One control period per :meth:`OmniLiveVehicle.step`, tracking the agent's reference of the marker.
A ground vehicle has no height to gain or lose, so the autopilot-like modes map as:

* take-off: the backend creates the live vehicle (motors on, marker up) where it rests; there is
  no climb: the reference's height is ignored and the marker stays on the floor, so a backend
  should end a ground vehicle's take-off (and landing) move at once instead of waiting for a
  height it never reaches;
* hold / offboard: track the reference (marker down only while the reference says so);
* land: marker up and hold where it is, then the backend drops the live vehicle (motors off);
* estop: :meth:`OmniLiveVehicle.enable` ``(False)``: the motors go limp at once and the vehicle
  rolls to rest (or the backend drops it).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from vehicles.attitude import quaternion_of_matrix
from vehicles.omni_wheel.floor_plan import OmniSettings
from vehicles.omni_wheel.writing import FloorWriter
from vehicles.surface import Vec3


class MarkerReference(Protocol):
    """What the agent gives each tick (``vehicles.kind.LiveReference`` has these fields)."""

    @property
    def position_m_enu(self) -> Vec3:
        """Marker reference in [m], ENU (its height is ignored)."""
        ...

    @property
    def velocity_mps_enu(self) -> Vec3:
        """Feed-forward velocity in [m/s], ENU."""
        ...

    @property
    def pen_down(self) -> bool:
        """The marker is meant to touch the floor."""
        ...


@dataclass(frozen=True)
class OmniLiveState:
    """The vehicle after a tick (true values; the fields of ``vehicles.kind.LiveState``)."""

    position_m_enu: Vec3
    """Marker point (the vehicle's reference point) on the floor in [m], ENU."""
    velocity_mps_enu: Vec3
    """Velocity of the middle axle in [m/s], ENU."""
    pen_tip_m_enu: Vec3
    """Where the marker is in [m], ENU."""
    pen_contact: bool
    """The marker touches the floor."""
    pen_width_m: float
    """Width in [m] of the line laid now (0 with the marker up)."""
    force_n: float | None = None
    """Not sensed by this kind."""
    attitude_xyzw_enu: tuple[float, float, float, float] | None = None
    """The rear part's attitude: quaternion (x, y, z, w), body FLU -> world ENU."""


def _vec(values: np.ndarray) -> Vec3:
    return (float(values[0]), float(values[1]), float(values[2]))


class OmniLiveVehicle:
    """A ground writer at rest at its start, motors on."""

    def __init__(self, start_m_enu: Vec3, settings: OmniSettings, *, seed: int = 0) -> None:
        self.settings = settings
        self.dt_s = settings.control_dt_s
        self._writer = FloorWriter(settings, np.asarray(start_m_enu, dtype=np.float64), seed=seed)

    def enable(self, on: bool) -> None:
        """Motors on, or off (estop: no torque, no marker)."""
        self._writer.world.enabled[0] = on

    def step(self, reference: MarkerReference) -> None:
        """Advance one tick tracking ``reference`` (height ignored; pen only while enabled)."""
        enabled = bool(self._writer.world.enabled[0])
        self._writer.tick(
            np.asarray(reference.position_m_enu, dtype=np.float64),
            np.asarray(reference.velocity_mps_enu, dtype=np.float64),
            bool(reference.pen_down) and enabled,
        )

    def state(self) -> OmniLiveState:
        """The vehicle now."""
        truth = self._writer.world.truth(0)
        down = self._writer.pen_is_down
        return OmniLiveState(
            position_m_enu=_vec(truth.pen_m_enu),
            velocity_mps_enu=_vec(truth.base_velocity_mps_enu),
            pen_tip_m_enu=_vec(truth.pen_m_enu),
            pen_contact=down,
            pen_width_m=self.settings.marker_width_m if down else 0.0,
            attitude_xyzw_enu=quaternion_of_matrix(truth.rotation),
        )

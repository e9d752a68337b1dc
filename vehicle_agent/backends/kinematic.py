"""An ideal vehicle: tracks every setpoint exactly, climbs and descends at a fixed speed.

No dynamics, so it costs next to nothing per tick: for unit tests of the agent, previews, and
benchmarks of the fleet with many agents. ``KinematicVehicle`` is the pure, synchronous core;
``KinematicBackend`` wraps it in the :class:`~vehicle_agent.backends.base.VehicleBackend` protocol.
"""

from __future__ import annotations

import math

from vehicle_agent.backends.base import (
    BackendError,
    BackendMode,
    Setpoint,
    SynchronousBackend,
    Vec3,
    VehicleSnapshot,
)


class KinematicVehicle:
    """A point that follows orders exactly (synchronous, pure)."""

    def __init__(self, home_m_enu: Vec3, *, dt_s: float = 0.01, climb_mps: float = 0.5) -> None:
        self.home_m_enu = home_m_enu
        """Where it rests on the ground in [m], ENU."""
        self.dt_s = dt_s
        """Length of one tick in [s]."""
        self.climb_mps = climb_mps
        """Vertical speed of take-off and landing in [m/s]."""
        self.t_s = 0.0
        self.mode: BackendMode = "idle"
        self.position_m_enu: Vec3 = home_m_enu
        self.velocity_mps_enu: Vec3 = (0.0, 0.0, 0.0)
        self._target_z_m = home_m_enu[2]
        self.pen_z_m: float | None = None
        """Height in [m] at or below which the pen touches (None: unknown contact)."""

    def snapshot(self) -> VehicleSnapshot:
        """The vehicle now."""
        z = self.position_m_enu[2]
        contact = None if self.pen_z_m is None else z <= self.pen_z_m
        return VehicleSnapshot(
            t_s=self.t_s,
            position_m_enu=self.position_m_enu,
            velocity_mps_enu=self.velocity_mps_enu,
            armed=self.mode not in ("idle", "estop"),
            mode=self.mode,
            on_ground=self.mode in ("idle", "estop"),
            battery_fraction=1.0,
            pen_contact=contact,
        )

    def takeoff(self, hover_m_enu: Vec3) -> None:
        """Start climbing straight up to the height of ``hover_m_enu``."""
        if self.mode != "idle":
            raise BackendError(f"cannot take off in mode {self.mode}")
        self.mode, self._target_z_m = "takeoff", hover_m_enu[2]

    def land(self) -> None:
        """Start descending to the ground height of home."""
        if self.mode in ("idle", "estop"):
            return
        self.mode, self._target_z_m = "landing", self.home_m_enu[2]

    def estop(self) -> None:
        """Stop where it is and drop to the ground at once."""
        x, y, _ = self.position_m_enu
        self.mode = "estop"
        self.position_m_enu = (x, y, self.home_m_enu[2])
        self.velocity_mps_enu = (0.0, 0.0, 0.0)

    def recover(self) -> None:
        """After ``estop``: ``idle`` where it stands, ready to take off again."""
        if self.mode not in ("idle", "estop"):
            raise BackendError(f"cannot recover in mode {self.mode}: it is not at rest")
        self.mode = "idle"

    def tick(self, setpoint: Setpoint | None) -> VehicleSnapshot:
        """Advance one period."""
        self.t_s += self.dt_s
        if setpoint is not None:
            if self.mode not in ("hold", "offboard"):
                raise BackendError(f"setpoint refused in mode {self.mode}")
            self.mode = "offboard"
            self.position_m_enu = setpoint.position_m_enu
            self.velocity_mps_enu = setpoint.velocity_mps_enu
        elif self.mode in ("takeoff", "landing"):
            self._vertical_step()
        elif self.mode == "offboard":
            self.mode = "hold"
            self.velocity_mps_enu = (0.0, 0.0, 0.0)
        return self.snapshot()

    def _vertical_step(self) -> None:
        x, y, z = self.position_m_enu
        dz = self._target_z_m - z
        step = math.copysign(min(abs(dz), self.climb_mps * self.dt_s), dz)
        self.position_m_enu = (x, y, z + step)
        self.velocity_mps_enu = (0.0, 0.0, step / self.dt_s)
        if abs(self._target_z_m - (z + step)) < 1e-12:
            self.velocity_mps_enu = (0.0, 0.0, 0.0)
            self.mode = "hold" if self.mode == "takeoff" else "idle"


class KinematicBackend(SynchronousBackend[KinematicVehicle]):
    """:class:`KinematicVehicle` behind the async backend protocol."""

    def __init__(self, home_m_enu: Vec3, *, control_period_s: float = 0.01) -> None:
        super().__init__(KinematicVehicle(home_m_enu, dt_s=control_period_s))

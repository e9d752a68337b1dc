"""The contract between a vehicle agent and the vehicle it flies: in-process sim or MAVLink.

The agent runs a fixed-rate loop (100 Hz by default). Each control period it calls
:meth:`VehicleBackend.tick` exactly once, with a :class:`Setpoint` while it wants the vehicle to
track a reference (writing, returning, hovering in place), or with ``None`` while the backend's
own mode is in charge (on the ground, taking off, landing, stopped). ``tick`` returns the vehicle's
state at the end of that period as a :class:`VehicleSnapshot`.

Mode changes are commands that return as soon as the vehicle accepted them; their progress is seen
in the following snapshots (``mode``, ``on_ground``):

======================  ===============================================================
call                    what the backend does, seen through ``VehicleSnapshot.mode``
======================  ===============================================================
``start()``             connect / create the vehicle; mode ``idle`` (on the ground, disarmed)
``takeoff(hover)``      arm and climb to ``hover`` on its own; ``takeoff`` then ``hold``
``tick(setpoint)``      track the setpoint for one period (only airborne); ``offboard``
``tick(None)``          continue the current mode; after ``offboard`` it holds the last point
``land()``              descend at the current horizontal position; ``landing`` then ``idle``
``estop()``             motors off at once; ``estop`` (the vehicle drops; sim: comes to rest)
``recover()``           after ``estop`` or a fault, once it rests disarmed on the ground: ``idle``
                        again, so that the next ``takeoff`` goes through its normal checks
``close()``             release the connection / the simulated vehicle
======================  ===============================================================

Time: a backend never reads a global clock inside ``tick``. The in-process simulator advances its
own time by one control period per call (so a faster-than-real-time loop is the same code); a
MAVLink backend stamps messages with ``now_s`` passed by the agent. World frame ENU and SI units
everywhere; conversion to NED happens only inside the MAVLink backend.

Creating a backend: ``vehicle_agent.agent.make_backend(setup)`` builds the simulator itself and,
for ``backend: mavlink`` vehicles, calls
``vehicle_agent.backends.mavlink.create.create_backend(setup)`` with the agent's ``VehicleSetup``
(show, vehicle id, board frame, runner config, time scale).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Generic, Literal, Protocol, TypeVar, runtime_checkable

Vec3 = tuple[float, float, float]
"""A 3-vector in the world frame ENU."""
Quaternion = tuple[float, float, float, float]
"""A unit quaternion (x, y, z, w)."""

BackendMode = Literal["idle", "takeoff", "hold", "offboard", "landing", "estop"]
"""What the vehicle is doing, as its autopilot (or the simulator) sees it."""


class BackendError(RuntimeError):
    """A backend cannot do what was asked (no connection, rejected command, not airborne)."""


class CommandRefusedError(BackendError):
    """The vehicle declined a command but is healthy (e.g. its pre-arm checks failed): the agent
    may try again later. Any other :class:`BackendError` from ``takeoff`` is a fault."""


class NotReadyError(CommandRefusedError):
    """Nothing was asked of the vehicle: it says it cannot take off now (its pre-arm checks
    fail: :attr:`VehicleSnapshot.preflight`); the agent takes off once it says it can."""


@dataclass(frozen=True)
class Setpoint:
    """The reference for one control period, from the planned trajectory or a hold point."""

    position_m_enu: Vec3
    """Reference position in [m], world frame ENU."""
    velocity_mps_enu: Vec3 = (0.0, 0.0, 0.0)
    """Reference velocity in [m/s] (feed-forward)."""
    acceleration_mps2_enu: Vec3 = (0.0, 0.0, 0.0)
    """Reference acceleration in [m/s^2] (feed-forward)."""
    pen_down: bool = False
    """True while the brush is meant to touch the board (for vehicles with an actuated pen)."""
    force_n: float | None = None
    """Wanted normal contact force in [N] (kinds that control force; None: the kind's own)."""


@dataclass(frozen=True)
class LinkHealth:
    """What a backend measures of its link to the vehicle and the vehicle's estimator, for the
    agent's preflight (``vehicle_agent/preflight.py``); a figure it does not measure is None."""

    link_age_s: float | None = None
    """Age in [s] of the autopilot's latest heartbeat."""
    link_loss_fraction: float | None = None
    """Share of the autopilot's recent messages lost on the link, 0..1 (from their sequence
    numbers); None until enough have come to say."""
    estimator: str | None = None
    """What the autopilot's estimator lacks, in words (None: healthy, or not reported)."""
    mocap_age_s: float | None = None
    """Age in [s] of the latest mocap pose forwarded to the autopilot (None: no mocap
    forwarded); infinite while none has been."""
    fence: str | None = None
    """Why the autopilot's own fence is not in place, in words (None: it is, or not asked)."""


@dataclass(frozen=True)
class VehicleSnapshot:
    """The vehicle at the end of one control period."""

    t_s: float
    """Backend time in [s]: simulated time, or the agent clock when the state was read."""
    position_m_enu: Vec3
    """Position in [m] of the vehicle reference point, world frame ENU."""
    velocity_mps_enu: Vec3
    """Velocity in [m/s], world frame ENU."""
    armed: bool
    """Motors armed."""
    mode: BackendMode
    """What the vehicle is doing (see the module docstring)."""
    on_ground: bool
    """Resting on the ground (landed or never took off)."""
    battery_fraction: float | None = None
    """Charge left in the battery over its rated capacity, 0..1, when known."""
    battery_voltage_v: float | None = None
    """Battery terminal voltage in [V] (under the present load), when known."""
    battery_minutes_left: float | None = None
    """Minutes until the battery is empty, when known: at the kind's cruise draw (the sim), or
    as the autopilot predicts from its recent draw (MAVLink ``time_remaining``)."""
    fault: str | None = None
    """A fault that stops flying (lost link, failsafe, crash), in words; None when healthy."""
    pen_contact: bool | None = None
    """Whether the pen touches the board, when the backend knows (the simulator; MAVLink: the
    kind's pen model, from the pose)."""
    pen_tip_m_enu: Vec3 | None = None
    """Where the pen tip is in [m], ENU, when the backend knows: the writing point (brush tip,
    sponge, marker) of ink metrics and of ``Telemetry.writing_point_m_enu``."""
    attitude_xyzw_enu: Quaternion | None = None
    """The body's attitude, when the backend knows: unit quaternion (x, y, z, w) turning body
    FLU into world ENU (the simulator's truth; MAVLink: the autopilot's ATTITUDE)."""
    pen_width_m: float | None = None
    """Width in [m] of the stroke the pen lays now (0 without contact), when known."""
    force_n: float | None = None
    """Measured normal contact force in [N], for kinds that sense it."""
    autopilot_mode: str | None = None
    """The autopilot's own name of its flight mode (``GUIDED``, ``OFFBOARD``, ``AUTO.LAND``...),
    for the event log; None for a backend without an autopilot."""
    true_position_m_enu: Vec3 | None = None
    """Where the vehicle reference point truly is in [m], ENU, when the backend knows it apart
    from the vehicle's own estimate (a simulator's truth behind an autopilot); None otherwise."""
    preflight: str | None = None
    """Why it cannot take off now, in the autopilot's own words (its failing pre-arm check, e.g.
    ``Preflight Fail: horizontal velocity unstable``); None: it can (or the backend has no
    autopilot). The agent publishes it, and no job is given to the vehicle meanwhile: arming
    would only be refused."""
    health: LinkHealth | None = None
    """The link and estimator figures of the agent's preflight (None: the backend has no link
    to check, e.g. the in-process simulator)."""


@runtime_checkable
class VehicleBackend(Protocol):
    """One vehicle, as the agent drives it. Implementations: ``sim.SimBackend``, ``mavlink``."""

    @property
    def control_period_s(self) -> float:
        """Length in [s] of one ``tick`` (1 / control rate, 0.01 at 100 Hz)."""
        ...

    async def start(self) -> VehicleSnapshot:
        """Connect to / create the vehicle; returns its first state (on the ground)."""
        ...

    async def takeoff(self, hover_m_enu: Vec3) -> None:
        """Arm and climb to ``hover_m_enu``; the mode goes ``takeoff`` then ``hold``."""
        ...

    async def tick(self, setpoint: Setpoint | None, now_s: float) -> VehicleSnapshot:
        """Advance one control period; ``now_s`` is the agent's clock in [s]."""
        ...

    async def land(self) -> None:
        """Descend at the current horizontal position; mode ``landing`` then ``idle``."""
        ...

    async def estop(self) -> None:
        """Cut the motors now; mode ``estop``."""
        ...

    async def recover(self) -> None:
        """Leave ``estop`` (or a fault the backend found) for ``idle``: only a vehicle resting
        disarmed on the ground, with a live link, may; raises :class:`BackendError` saying why
        not. The next take-off then goes through all its usual checks (an autopilot re-arms)."""
        ...

    async def close(self) -> None:
        """Release the vehicle; safe to call twice."""
        ...


class SynchronousVehicle(Protocol):
    """A vehicle stepped in-process, one control period per ``tick`` (kinematic, simulated)."""

    dt_s: float
    """Length of one tick in [s]."""

    def snapshot(self) -> VehicleSnapshot: ...

    def takeoff(self, hover_m_enu: Vec3) -> None: ...

    def tick(self, setpoint: Setpoint | None) -> VehicleSnapshot: ...

    def land(self) -> None: ...

    def estop(self) -> None: ...

    def recover(self) -> None: ...


@runtime_checkable
class BatterySwap(Protocol):
    """A backend whose battery the crew can change: the simulator (a full pack), an autopilot
    (told where it keeps a count: ``mavlink/battery.py``)."""

    async def swap_battery(self) -> None:
        """A fresh pack is in: only at rest on the ground (raises :class:`BackendError`)."""
        ...


V = TypeVar("V", bound=SynchronousVehicle)


class SynchronousBackend(Generic[V]):
    """A :class:`SynchronousVehicle` behind the async :class:`VehicleBackend` protocol (the
    vehicle's own time advances per ``tick``; ``now_s`` is ignored)."""

    def __init__(self, vehicle: V) -> None:
        self.vehicle = vehicle

    @property
    def control_period_s(self) -> float:
        return self.vehicle.dt_s

    async def start(self) -> VehicleSnapshot:
        return self.vehicle.snapshot()

    async def takeoff(self, hover_m_enu: Vec3) -> None:
        self.vehicle.takeoff(hover_m_enu)

    async def tick(self, setpoint: Setpoint | None, now_s: float) -> VehicleSnapshot:
        return self.vehicle.tick(setpoint)

    async def land(self) -> None:
        self.vehicle.land()

    async def estop(self) -> None:
        self.vehicle.estop()

    async def recover(self) -> None:
        self.vehicle.recover()

    async def close(self) -> None:
        return None

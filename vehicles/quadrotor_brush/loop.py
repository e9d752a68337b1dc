"""The brush quadrotor's one closed loop: mocap -> position controller -> inner loop -> world.

:class:`ClosedLoop` advances N vehicles one control tick; the batch flight
(:class:`vehicles.quadrotor_brush.flight.Flight`), a fleet host's vehicles in flight
(:class:`QuadrotorFleet`) and the live simulated vehicle of an agent's ``sim`` backend
(:class:`SimulatedQuadrotor`, a fleet of one) all tick through it, so they fly alike.

Why a fleet: on N = 1 the loop is ~60 small numpy operations of ~1-2 us each (about 0.2 ms a
tick), while on N vehicles at once it costs about as much in all (``benchmarks/bench_sim.py``:
4.5 us per vehicle-tick at N = 100). A fleet keeps the vehicles in flight as rows of one loop;
a vehicle that joins or leaves (take-off, landing) is stacked in or taken out, carrying its own
state and noise streams, so it flies exactly as it would alone.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from vehicles.attitude import quaternions_of_euler
from vehicles.kind import LiveReference, LiveState
from vehicles.quadrotor_brush.control.config import ControllerConfig
from vehicles.quadrotor_brush.control.controller import PositionController, ReferenceTick
from vehicles.quadrotor_brush.control.inner import InnerLoopSetpoint
from vehicles.quadrotor_brush.dynamics import InnerLoopCommand
from vehicles.quadrotor_brush.params import WorldParams
from vehicles.quadrotor_brush.world import World
from vehicles.surface import Vec3

FloatArray = NDArray[np.float64]


class ClosedLoop:
    """N simulated quadrotors and their controllers, starting at rest at ``start_m_enu`` (N, 3)."""

    def __init__(
        self, world: WorldParams, controller: ControllerConfig, start_m_enu: ArrayLike, seed: int
    ) -> None:
        start = np.asarray(start_m_enu, dtype=np.float64)
        self.dt_s = world.dt_s
        self.world = World(world, start, seed=seed)
        self.controller = PositionController(controller, self.dt_s, start)

    def take(self, rows: Sequence[int]) -> ClosedLoop:
        """The loop of vehicles ``rows`` (in that order), each as it stands."""
        out = object.__new__(ClosedLoop)
        out.dt_s = self.dt_s
        out.world = self.world.take(rows)
        out.controller = self.controller.take(rows)
        return out

    @classmethod
    def stack(cls, loops: Sequence[ClosedLoop]) -> ClosedLoop:
        """One loop of the vehicles of ``loops`` (same world and controller), in order."""
        out = object.__new__(cls)
        out.dt_s = loops[0].dt_s
        out.world = World.stack([loop.world for loop in loops])
        out.controller = PositionController.stack([loop.controller for loop in loops])
        return out

    def advance(self, reference: ReferenceTick) -> InnerLoopSetpoint:
        """One control tick: read the mocap frame, compute the inner-loop command for
        ``reference`` (the body reference, (N, 3) each), step the world."""
        setpoint = self.controller.update(self.world.mocap_frame().position_m_enu, reference)
        self.world.step(
            InnerLoopCommand(
                setpoint.throttle, setpoint.roll_rad, setpoint.pitch_rad, setpoint.yaw_rad
            )
        )
        return setpoint


class QuadrotorFleet:
    """Live simulated quadrotors of one world and controller, stepped together (see
    :class:`vehicles.kind.SimulatedFleet`): row ``i`` of the loop is ``_members[i]``."""

    def __init__(self, world: WorldParams, controller: ControllerConfig) -> None:
        self.world_params = world
        self.controller_config = controller
        self.dt_s = world.dt_s
        self._loop: ClosedLoop | None = None
        self._members: list[FleetQuadrotor] = []
        self._states: list[LiveState] | None = None

    def __len__(self) -> int:
        return len(self._members)

    def vehicle(self, start_m_enu: Vec3, *, seed: int) -> FleetQuadrotor:
        """A vehicle at rest at ``start_m_enu`` joins (seeded as a vehicle flying alone)."""
        joining = ClosedLoop(self.world_params, self.controller_config, [start_m_enu], seed)
        self._loop = joining if self._loop is None else ClosedLoop.stack([self._loop, joining])
        member = FleetQuadrotor(self)
        self._reorder([*self._members, member])
        return member

    def release(self, vehicle: object) -> None:
        """``vehicle`` leaves (landed, stopped); unknown vehicles are ignored."""
        keep = [i for i, m in enumerate(self._members) if m is not vehicle]
        if len(keep) == len(self._members) or self._loop is None:
            return
        self._loop = self._loop.take(keep) if keep else None
        self._reorder([self._members[i] for i in keep])

    def step(self) -> None:
        """Advance every vehicle given a reference since the last step by one tick, in one
        call; the others (their own tick not come yet) wait as they stand."""
        members, loop = self._members, self._loop
        due: list[int] = []
        references: list[LiveReference] = []
        for i, member in enumerate(members):
            if member.reference is not None:
                due.append(i)
                references.append(member.reference)
        if not due or loop is None:
            return
        waiting = [i for i, m in enumerate(members) if m.reference is None]
        moving = loop if not waiting else loop.take(due)
        moving.advance(
            ReferenceTick(
                position_m_enu=np.array([r.position_m_enu for r in references]),
                velocity_mps_enu=np.array([r.velocity_mps_enu for r in references]),
                acceleration_mps2_enu=np.array([r.acceleration_mps2_enu for r in references]),
            )
        )
        for i in due:
            members[i].reference = None
        if waiting:
            self._loop = ClosedLoop.stack([moving, loop.take(waiting)])
            self._reorder([members[i] for i in due + waiting])
        self._states = None

    def state_of(self, member: FleetQuadrotor) -> LiveState:
        """A member now, with its brush (the brushes of all members worked out at once)."""
        if self._states is None:
            self._states = self._live_states()
        return self._states[member.row]

    def _reorder(self, members: list[FleetQuadrotor]) -> None:
        self._members = members
        for row, member in enumerate(members):
            member.row = row
        self._states = None

    def _live_states(self) -> list[LiveState]:
        if self._loop is None:
            return []
        world = self._loop.world
        brush = world.brush()
        rows = zip(
            world.state.position_m_enu.tolist(),
            world.state.velocity_mps_enu.tolist(),
            brush.tip_m_enu.tolist(),
            brush.contact.tolist(),
            brush.width_m.tolist(),
            quaternions_of_euler(world.state.attitude_rad).tolist(),
            strict=True,
        )
        return [
            LiveState(
                position_m_enu=(p[0], p[1], p[2]),
                velocity_mps_enu=(v[0], v[1], v[2]),
                pen_tip_m_enu=(t[0], t[1], t[2]),
                pen_contact=contact,
                pen_width_m=width if contact else 0.0,
                attitude_xyzw_enu=(q[0], q[1], q[2], q[3]),
            )
            for p, v, t, contact, width, q in rows
        ]


class FleetQuadrotor:
    """One vehicle of a :class:`QuadrotorFleet`: ``step`` records its reference, the fleet's
    ``step`` flies it."""

    def __init__(self, fleet: QuadrotorFleet) -> None:
        self._fleet = fleet
        self.dt_s = fleet.dt_s
        self.row = 0
        """Its row in the fleet's loop (the fleet keeps it up to date)."""
        self.reference: LiveReference | None = None
        """The reference of its coming tick, until the fleet steps."""

    def step(self, reference: LiveReference) -> None:
        """Track ``reference`` at the fleet's next step (the body reference: position, velocity
        and acceleration feed-forward; the pen follows the body)."""
        self.reference = reference

    def state(self) -> LiveState:
        """The vehicle now, with its brush."""
        return self._fleet.state_of(self)


class SimulatedQuadrotor:
    """One live simulated quadrotor (see :class:`vehicles.kind.SimulatedVehicle`): a fleet of
    one, stepped at each ``step``."""

    def __init__(
        self, start_m_enu: Vec3, world: WorldParams, controller: ControllerConfig, *, seed: int
    ) -> None:
        self._fleet = QuadrotorFleet(world, controller)
        self._vehicle = self._fleet.vehicle(start_m_enu, seed=seed)
        self.dt_s = self._fleet.dt_s

    def step(self, reference: LiveReference) -> None:
        """One tick tracking ``reference`` (the body reference)."""
        self._vehicle.step(reference)
        self._fleet.step()

    def state(self) -> LiveState:
        """The vehicle now, with its brush."""
        return self._vehicle.state()

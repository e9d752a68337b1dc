"""The brush quadrotor's one closed loop: mocap -> position controller -> inner loop -> world.

:class:`ClosedLoop` advances N vehicles one control tick; the batch flight
(:class:`vehicles.quadrotor_brush.flight.Flight`) and the live simulated vehicle of the agent's
``sim`` backend (:class:`SimulatedQuadrotor`) both tick through it, so they fly alike.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from vehicles.kind import LiveReference, LiveState
from vehicles.quadrotor_brush.control.controller import (
    ControllerConfig,
    PositionController,
    ReferenceTick,
)
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


def _vec(row: FloatArray) -> Vec3:
    x, y, z = row.tolist()
    return (x, y, z)


class SimulatedQuadrotor:
    """One live simulated quadrotor (see :class:`vehicles.kind.SimulatedVehicle`)."""

    def __init__(
        self, start_m_enu: Vec3, world: WorldParams, controller: ControllerConfig, *, seed: int
    ) -> None:
        self._loop = ClosedLoop(world, controller, [start_m_enu], seed)
        self.dt_s = self._loop.dt_s

    def step(self, reference: LiveReference) -> None:
        """One tick tracking ``reference`` (the body reference: position, velocity and
        acceleration feed-forward; the pen follows the body)."""
        self._loop.advance(
            ReferenceTick(
                position_m_enu=np.asarray([reference.position_m_enu]),
                velocity_mps_enu=np.asarray([reference.velocity_mps_enu]),
                acceleration_mps2_enu=np.asarray([reference.acceleration_mps2_enu]),
            )
        )

    def state(self) -> LiveState:
        """The vehicle now, with its brush."""
        world = self._loop.world
        brush = world.brush()
        contact = bool(brush.contact[0])
        return LiveState(
            position_m_enu=_vec(world.state.position_m_enu[0]),
            velocity_mps_enu=_vec(world.state.velocity_mps_enu[0]),
            pen_tip_m_enu=_vec(brush.tip_m_enu[0]),
            pen_contact=contact,
            pen_width_m=float(brush.width_m[0]) if contact else 0.0,
        )

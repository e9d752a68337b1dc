"""The simulated world of N writing quadrotors: dynamics, wind, ground effect, mocap, brush.

One call of :meth:`World.step` advances every vehicle by one control tick under held inner-loop
commands. Time is the world's own tick count; nothing here reads a clock or performs I/O.

Vehicles can be taken out of a world (:meth:`World.take`) and worlds put together
(:meth:`World.stack`): a fleet host steps the vehicles that fly at the same time in one world,
each vehicle flying exactly as it would alone (its own noise streams, its own delay line).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sim.errors import SimError
from sim.noise import MOCAP_STREAM, WIND_STREAM, NormalBlocks
from vehicles.quadrotor_brush.brush import BrushState, brush_state
from vehicles.quadrotor_brush.dynamics import (
    InnerLoopCommand,
    QuadrotorDynamics,
    QuadrotorState,
    body_z_axis,
    ground_effect_gain,
)
from vehicles.quadrotor_brush.params import WorldParams

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class MocapFrame:
    """What motion capture delivers at one control tick."""

    capture_time_s: float
    """World time in [s] at which the positions were true (now minus the latency)."""
    position_m_enu: FloatArray
    """Measured positions in [m], shape (N, 3), with noise."""


class World:
    """N vehicles stepping together; same parameters, seed and commands give the same result."""

    def __init__(
        self,
        params: WorldParams,
        initial_position_m_enu: ArrayLike,
        *,
        seed: int,
        initial_yaw_rad: ArrayLike | None = None,
    ) -> None:
        p0 = np.array(initial_position_m_enu, dtype=np.float64).reshape(-1, 3)
        if p0.shape[0] == 0 or not bool(np.all(np.isfinite(p0))):
            raise SimError("needs finite (N, 3) positions, N >= 1", field="initial_position_m_enu")
        self.params = params
        self.n_vehicles = n = p0.shape[0]
        self.tick = 0
        self._dyn = QuadrotorDynamics(
            params.quadrotor, params.physics_dt_s, params.physics_substeps
        )
        yaw = np.zeros(n) if initial_yaw_rad is None else np.broadcast_to(initial_yaw_rad, (n,))
        attitude = np.zeros((n, 3))
        attitude[:, 2] = yaw
        gain = self._ground_gain(p0)
        self.state = QuadrotorState(
            position_m_enu=p0,
            velocity_mps_enu=np.zeros((n, 3)),
            attitude_rad=attitude,
            attitude_rate_radps=np.zeros((n, 3)),
            thrust_mps2=params.quadrotor.gravity_mps2 / gain,
            body_z_enu=body_z_axis(attitude),
        )
        self._wind_noise = NormalBlocks(seed, n, WIND_STREAM)
        self._mocap_noise = NormalBlocks(seed, n, MOCAP_STREAM)
        wind = params.wind
        self._wind_mean = np.asarray(wind.mean_mps_enu, dtype=np.float64)
        self._gust_sigma = np.asarray(wind.gust_sigma_mps_enu, dtype=np.float64)
        self._gust_keep = math.exp(-params.dt_s / wind.gust_time_constant_s)
        self._gust_new = math.sqrt(1.0 - self._gust_keep**2)
        self.gust_mps_enu: FloatArray = self._gust_sigma * self._wind_noise.draw()
        latency_steps = round(params.mocap.latency_s / params.physics_dt_s)
        s = params.physics_substeps
        self._mocap_ticks_back = -(-latency_steps // s)
        self._mocap_capture_after = self._mocap_ticks_back * s - latency_steps
        self.mocap_latency_s = latency_steps * params.physics_dt_s
        self._mocap_queue: list[FloatArray] = [p0.copy()] * self._mocap_ticks_back
        self._frame = self._capture_frame()

    def take(self, rows: Sequence[int]) -> World:
        """A world of vehicles ``rows`` of this one (in that order), each as it stands."""
        index = list(rows)
        out = copy.copy(self)
        out.n_vehicles = len(index)
        out.state = self.state.take(index)
        out._wind_noise = self._wind_noise.take(index)
        out._mocap_noise = self._mocap_noise.take(index)
        out.gust_mps_enu = self.gust_mps_enu[index]
        out._mocap_queue = [positions[index] for positions in self._mocap_queue]
        out._frame = MocapFrame(self._frame.capture_time_s, self._frame.position_m_enu[index])
        return out

    @classmethod
    def stack(cls, worlds: Sequence[World]) -> World:
        """One world of the vehicles of ``worlds`` (same parameters), in order, each as it
        stands; its clock is the first world's."""
        first = worlds[0]
        if any(w.params != first.params for w in worlds):
            raise SimError("worlds with different parameters", field="params")
        out = copy.copy(first)
        out.n_vehicles = sum(w.n_vehicles for w in worlds)
        out.state = QuadrotorState.stack([w.state for w in worlds])
        out._wind_noise = NormalBlocks.stack([w._wind_noise for w in worlds])
        out._mocap_noise = NormalBlocks.stack([w._mocap_noise for w in worlds])
        out.gust_mps_enu = np.concatenate([w.gust_mps_enu for w in worlds])
        out._mocap_queue = [
            np.concatenate(tick) for tick in zip(*(w._mocap_queue for w in worlds), strict=True)
        ]
        frames = np.concatenate([w._frame.position_m_enu for w in worlds])
        out._frame = MocapFrame(first._frame.capture_time_s, frames)
        return out

    @property
    def time_s(self) -> float:
        """World time in [s]: ticks stepped times the control tick."""
        return self.tick * self.params.dt_s

    @property
    def wind_mps_enu(self) -> FloatArray:
        """Wind velocity at each vehicle during the coming tick in [m/s], shape (N, 3)."""
        return self._wind_mean + self.gust_mps_enu

    @property
    def hover_throttle(self) -> FloatArray:
        """Throttle that balances gravity at the current heights (ground effect included)."""
        q = self.params.quadrotor
        gain = self._ground_gain(self.state.position_m_enu)
        return q.throttle_per_mps2 * q.gravity_mps2 / gain

    def _ground_gain(self, position_m_enu: FloatArray) -> FloatArray:
        q = self.params.quadrotor
        height = position_m_enu[:, 2] + q.rotor_height_m - self.params.board_height_m
        return ground_effect_gain(height, q.rotor_radius_m)

    def mocap_frame(self) -> MocapFrame:
        """The newest motion-capture frame available now (latency and noise applied, drawn once
        per tick: asking twice gives the same frame)."""
        return self._frame

    def _capture_frame(self) -> MocapFrame:
        true = self.state.position_m_enu if self._mocap_ticks_back == 0 else self._mocap_queue[0]
        noisy = true + self.params.mocap.noise_std_m * self._mocap_noise.draw()
        return MocapFrame(self.time_s - self.mocap_latency_s, noisy)

    def brush(self) -> BrushState:
        """Brush tip, press, width and contact of every vehicle now."""
        return brush_state(
            self.params.brush,
            self.state.position_m_enu,
            self.state.body_z_enu,
            self.params.board_height_m,
        )

    def step(self, command: InnerLoopCommand) -> None:
        """Advance every vehicle by one control tick holding ``command``."""
        gain = self._ground_gain(self.state.position_m_enu)
        capture = self._mocap_capture_after if self._mocap_ticks_back > 0 else None
        captured = self._dyn.advance(self.state, command, self.wind_mps_enu, gain, capture)
        if captured is not None:
            self._mocap_queue.append(captured)
            self._mocap_queue.pop(0)
        self.gust_mps_enu = (
            self._gust_keep * self.gust_mps_enu
            + (self._gust_new * self._gust_sigma) * self._wind_noise.draw()
        )
        self.tick += 1
        self._frame = self._capture_frame()

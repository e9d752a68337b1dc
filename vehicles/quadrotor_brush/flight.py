"""The closed loop: reference samples + controller + simulated world -> flight log.

Pure and time-injected. :class:`Flight` runs one 100 Hz tick at a time (``step(t_s)``), as the
vehicle-agent process does against its clock; :func:`fly` runs a whole batch as fast as the CPU
allows. Both give bit-identical logs for the same inputs and seed.

Clock mapping: tick ``k`` happens at clock time ``start_time_s + k * dt``; the reference's
``t = 0`` is at ``start_time_s``. Before it the world hovered ``preroll_s`` on the first sample
(not recorded); after the reference's end it holds the last sample. Each tick: record the state,
read the mocap frame, compute the inner-loop command from the reference at the tick time, advance
the world one tick.

With ``FlightConfig.deviation`` set, a vehicle whose tracking error stays above the bound for longer
than its window ends the flight there (``Flight.abort``, ``FlightLog.abort_reason``): what the
agent does on a vehicle (lift the brush and stop writing), in batch form.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from planner.samples import TrajectorySamples
from vehicles.deviation import DeviationMonitor, DeviationTrip
from vehicles.quadrotor_brush.brush import BrushState, brush_state, writing_point
from vehicles.quadrotor_brush.control.controller import (
    ReferenceTick,
    body_reference,
)
from vehicles.quadrotor_brush.control.errors import ControlError
from vehicles.quadrotor_brush.control.inner import InnerLoopSetpoint
from vehicles.quadrotor_brush.flight_config import FlightConfig
from vehicles.quadrotor_brush.loop import ClosedLoop

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

_LOGGED = (
    "position_m_enu",
    "velocity_mps_enu",
    "body_z_enu",
    "accel_cmd_mps2_enu",
    "throttle",
    "thrust_mps2",
    "wind_mps_enu",
    "disturbance_estimate_mps2_enu",
)


@dataclass(frozen=True)
class FlightState:
    """A snapshot of N vehicles after a step (what telemetry publishes)."""

    time_s: float
    """Clock time of the snapshot in [s]."""
    position_m_enu: FloatArray
    """True positions in [m], shape (N, 3)."""
    velocity_mps_enu: FloatArray
    """True velocities in [m/s], shape (N, 3)."""
    estimated_position_m_enu: FloatArray
    """The controller's estimate in [m], shape (N, 3)."""
    reference_position_m_enu: FloatArray
    """Reference at the snapshot time in [m], shape (N, 3)."""
    pen_down: BoolArray
    """Whether the reference is writing, shape (N,)."""
    brush: BrushState
    """Brush tip, press, width, contact."""
    throttle: FloatArray
    """Last throttle command, shape (N,)."""
    done: bool
    """True once every reference and the settle time are over."""


@dataclass(frozen=True)
class FlightLog:
    """Everything recorded at each tick k (state at the tick time, before its command acts)."""

    t_s: FloatArray
    """Clock time of each tick in [s], shape (K,)."""
    reference_position_m_enu: FloatArray
    """Shape (K, N, 3)."""
    reference_velocity_mps_enu: FloatArray
    """Shape (K, N, 3)."""
    pen_down: BoolArray
    """Reference pen state, shape (K, N)."""
    position_m_enu: FloatArray
    """True vehicle reference point, shape (K, N, 3)."""
    velocity_mps_enu: FloatArray
    """True velocity, shape (K, N, 3)."""
    body_z_enu: FloatArray
    """Body z axis (brush axis, upwards), shape (K, N, 3)."""
    tip_m_enu: FloatArray
    """Brush tip, shape (K, N, 3)."""
    brush_width_m: FloatArray
    """Footprint diameter (0 without contact), shape (K, N)."""
    brush_contact: BoolArray
    """Tip on the board, shape (K, N)."""
    accel_cmd_mps2_enu: FloatArray
    """Outer-loop acceleration command, shape (K, N, 3)."""
    throttle: FloatArray
    """Throttle command, shape (K, N)."""
    thrust_mps2: FloatArray
    """Rotor specific thrust (out of ground effect), shape (K, N)."""
    wind_mps_enu: FloatArray
    """Wind at the vehicle, shape (K, N, 3)."""
    disturbance_estimate_mps2_enu: FloatArray
    """The estimator's external acceleration, shape (K, N, 3)."""
    brush_lever_m: float
    """Reference point to tip at nominal press [m] (the error is measured at that point)."""
    abort_reason: str | None = None
    """Why the flight ended early (a deviation abort), None when it was flown to its end."""

    def writing_point_error(self) -> FloatArray:
        """Writing-point error per tick and vehicle, shape (K, N, 3), [m]
        (:func:`vehicles.quadrotor_brush.brush.writing_point`)."""
        point = writing_point(self.position_m_enu, self.body_z_enu, self.brush_lever_m)
        error: FloatArray = point - self.reference_position_m_enu
        return error

    @property
    def n_vehicles(self) -> int:
        """N."""
        return int(self.position_m_enu.shape[1])


def _reference_grid(
    references: Sequence[TrajectorySamples], dt_s: float
) -> tuple[FloatArray, FloatArray, FloatArray, BoolArray]:
    """Resample every reference on the tick grid: p, v, a (K, N, 3), pen (K, N)."""
    duration = max(r.duration_s for r in references)
    k = int(np.ceil(duration / dt_s - 1e-9)) + 1
    t = np.arange(k) * dt_s
    n = len(references)
    p, v, a = (np.empty((k, n, 3)) for _ in range(3))
    pen = np.zeros((k, n), dtype=np.bool_)
    for i, ref in enumerate(references):
        for out, src in (
            (p, ref.position_m_enu),
            (v, ref.velocity_mps_enu),
            (a, ref.acceleration_mps2_enu),
        ):
            for axis in range(3):
                out[:, i, axis] = np.interp(t, ref.t_s, src[:, axis])
        nearest = np.clip(np.searchsorted(ref.t_s, t + 0.5 * dt_s) - 1, 0, ref.t_s.shape[0] - 1)
        pen[:, i] = ref.pen_down[nearest] & (t <= ref.duration_s + 0.5 * dt_s)
    return p, v, a, pen


class Flight:
    """Closed loop of N simulated vehicles, advanced tick by tick with an injected clock."""

    def __init__(
        self,
        references: Sequence[TrajectorySamples],
        config: FlightConfig | None = None,
        *,
        seed: int = 0,
        start_time_s: float = 0.0,
    ) -> None:
        if len(references) == 0:
            raise ControlError("needs at least one reference", field="references")
        self.config = cfg = config if config is not None else FlightConfig()
        self.dt_s = cfg.world.dt_s
        self.start_time_s = start_time_s
        self._p, self._v, self._a, self._pen = _reference_grid(references, self.dt_s)
        self._body_p, self._body_v, self._body_a = body_reference(
            cfg.controller, self._p, self._v, self._a, self.dt_s
        )
        self.duration_s = (self._p.shape[0] - 1) * self.dt_s + cfg.settle_s
        self.n_vehicles = len(references)
        self.loop = ClosedLoop(cfg.world, cfg.controller, self._body_p[0], seed)
        self.world, self.controller = self.loop.world, self.loop.controller
        self._setpoint: InnerLoopSetpoint | None = None
        self._records: dict[str, list[FloatArray]] = {name: [] for name in _LOGGED}
        self._ticks: list[int] = []
        self._k = 0
        self._monitors = (
            [DeviationMonitor(cfg.deviation) for _ in references] if cfg.deviation else []
        )
        self.abort: tuple[int, DeviationTrip] | None = None
        """(vehicle, trip) of the deviation that ended the flight early."""
        for _ in range(round(cfg.preroll_s / self.dt_s)):
            self._advance(0)

    @property
    def time_s(self) -> float:
        """Clock time of the world now in [s]."""
        return self.start_time_s + self._k * self.dt_s

    @property
    def done(self) -> bool:
        """True once the references and the settle time are flown, or the flight aborted."""
        return self.abort is not None or bool(self._k * self.dt_s >= self.duration_s - 1e-9)

    @property
    def abort_reason(self) -> str | None:
        """Why the flight ended early, in one sentence (None: it did not)."""
        if self.abort is None:
            return None
        vehicle, trip = self.abort
        return f"deviation abort of vehicle {vehicle} at t = {trip.tripped_at_s:.2f} s: " + (
            trip.message
        )

    def _row(self, tick: int) -> int:
        return min(tick, int(self._p.shape[0]) - 1)

    def step(self, t_s: float) -> FlightState:
        """Run every tick whose time is at or before ``t_s`` (a no-op if none) and return the
        state at the world's new time."""
        while self.time_s + 0.5 * self.dt_s <= t_s:
            self._tick()
        return self.state()

    def run(self) -> FlightLog:
        """Fly until :attr:`done`; return the log."""
        while not self.done:
            self._tick()
        return self.log()

    def _tick(self) -> None:
        row = self._row(self._k)
        world, ctrl = self.world, self.controller
        s = world.state
        rec = self._records
        rec["position_m_enu"].append(s.position_m_enu)
        rec["velocity_mps_enu"].append(s.velocity_mps_enu)
        rec["body_z_enu"].append(s.body_z_enu)
        rec["thrust_mps2"].append(s.thrust_mps2)
        rec["wind_mps_enu"].append(world.wind_mps_enu)
        setpoint = self._advance(row)
        rec["accel_cmd_mps2_enu"].append(ctrl.accel_cmd_mps2_enu)
        rec["throttle"].append(setpoint.throttle)
        rec["disturbance_estimate_mps2_enu"].append(ctrl.estimator.disturbance_mps2_enu)
        self._ticks.append(row)
        self._k += 1
        if self._monitors:
            self._watch(s.position_m_enu, row)

    def _watch(self, position_m_enu: FloatArray, row: int) -> None:
        """Feed each vehicle's tracking error (to the body reference it tracks) to its monitor."""
        errors = np.linalg.norm(position_m_enu - self._body_p[row], axis=1)
        for vehicle, monitor in enumerate(self._monitors):
            trip = monitor.update(float(errors[vehicle]), self.time_s)
            if trip is not None and self.abort is None:
                self.abort = (vehicle, trip)

    def _advance(self, row: int) -> InnerLoopSetpoint:
        """One control tick on reference row ``row``: mocap, controller, world step."""
        reference = ReferenceTick(self._body_p[row], self._body_v[row], self._body_a[row])
        self._setpoint = setpoint = self.loop.advance(reference)
        return setpoint

    def state(self) -> FlightState:
        """Snapshot at the world's current time."""
        row = self._row(self._k)
        s = self.world.state
        throttle = (
            self._setpoint.throttle if self._setpoint is not None else self.world.hover_throttle
        )
        return FlightState(
            time_s=self.time_s,
            position_m_enu=s.position_m_enu,
            velocity_mps_enu=s.velocity_mps_enu,
            estimated_position_m_enu=self.controller.estimator.position_m_enu,
            reference_position_m_enu=self._p[row],
            pen_down=self._pen[row],
            brush=self.world.brush(),
            throttle=throttle,
            done=self.done,
        )

    def log(self) -> FlightLog:
        """Everything recorded so far (K ticks)."""
        rows = np.asarray(self._ticks, dtype=np.int64)
        n = self.n_vehicles
        stacked = {
            name: (np.stack(values) if values else np.empty((0, n, 3)))
            for name, values in self._records.items()
        }
        cfg = self.config
        k = rows.shape[0]
        brush = brush_state(
            cfg.world.brush,
            stacked["position_m_enu"].reshape(-1, 3),
            stacked["body_z_enu"].reshape(-1, 3),
            cfg.world.board_height_m,
        )
        return FlightLog(
            tip_m_enu=brush.tip_m_enu.reshape(k, n, 3),
            brush_width_m=brush.width_m.reshape(k, n),
            brush_contact=brush.contact.reshape(k, n),
            t_s=self.start_time_s + np.arange(rows.shape[0], dtype=np.float64) * self.dt_s,
            reference_position_m_enu=self._p[rows],
            reference_velocity_mps_enu=self._v[rows],
            pen_down=self._pen[rows],
            brush_lever_m=cfg.world.brush.write_height_m,
            abort_reason=self.abort_reason,
            **stacked,
        )


def fly(
    references: Sequence[TrajectorySamples],
    config: FlightConfig | None = None,
    *,
    seed: int = 0,
) -> FlightLog:
    """Fly N vehicles (one reference each) to the end in one batch and return the log."""
    return Flight(references, config, seed=seed).run()

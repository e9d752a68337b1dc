"""Run simulated MAVLink vehicles in real time (or ``time_scale`` times faster) on one thread.

Each loop: step every vehicle's autopilot up to the current vehicle time, send the telemetry that is
due, then wait on all sockets until the next step (a setpoint is acted on as soon as it arrives).
Vehicle time is ``(wall - start) * time_scale``; every rate and timeout of a vehicle is in vehicle
time. If the machine falls behind by more than ``MAX_CATCH_UP_STEPS`` the vehicles slow down
instead of jumping.
"""

from __future__ import annotations

import select
import threading
import time
from collections.abc import Callable, Sequence
from types import TracebackType

from mavsim.config import VehicleConfig
from mavsim.endpoint import VehicleEndpoint
from mavsim.errors import MavsimError

MAX_CATCH_UP_STEPS = 20


class MavsimServer:
    """Several vehicles, each its own UDP endpoint and system id."""

    def __init__(
        self,
        configs: Sequence[VehicleConfig],
        *,
        time_scale: float = 1.0,
        wall_clock: Callable[[], float] = time.monotonic,
    ) -> None:
        if not time_scale > 0:
            raise MavsimError(f"time_scale must be > 0, got {time_scale}")
        ids = [c.system_id for c in configs]
        if len(set(ids)) != len(ids):
            raise MavsimError(f"system ids must be unique, got {ids}")
        self.time_scale = time_scale
        self._wall_clock = wall_clock
        self.endpoints: list[VehicleEndpoint] = []
        try:
            for config in configs:
                self.endpoints.append(VehicleEndpoint(config, wall_clock=wall_clock))
        except MavsimError:
            self.close()
            raise
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._t0 = wall_clock()
        self.error: BaseException | None = None
        self.longest_behind_s = 0.0
        """The furthest a vehicle's physics fell behind vehicle time before the loop came round
        to step it, in [s] of vehicle time: about one physics step, more when the host stalled
        this thread (the vehicle then flew its last setpoints that long, as no real one does)."""

    def endpoint(self, vehicle_id: str) -> VehicleEndpoint:
        """The endpoint of one vehicle by show id."""
        for ep in self.endpoints:
            if ep.config.vehicle_id == vehicle_id:
                return ep
        raise MavsimError(f"no simulated vehicle {vehicle_id!r}")

    def vehicle_time_s(self) -> float:
        """Current vehicle time in [s]."""
        return (self._wall_clock() - self._t0) * self.time_scale

    def run(self, stop: threading.Event | None = None) -> None:
        """Serve until ``stop`` is set (blocking)."""
        stop = stop or self._stop
        self._t0 = self._wall_clock()
        sockets = {ep.fileno(): ep for ep in self.endpoints}
        while not stop.is_set():
            now = self.vehicle_time_s()
            for ep in self.endpoints:
                self._catch_up(ep, now)
                ep.emit(now)
            next_step = min((ep.next_step_s for ep in self.endpoints), default=now + 0.01)
            wait_s = max(0.0, (next_step - self.vehicle_time_s()) / self.time_scale)
            readable, _, _ = select.select(list(sockets), [], [], min(wait_s, 0.05))
            for fd in readable:
                sockets[fd].receive(self.vehicle_time_s())

    def _catch_up(self, ep: VehicleEndpoint, now: float) -> None:
        self.longest_behind_s = max(self.longest_behind_s, now - ep.next_step_s)
        steps = 0
        while ep.next_step_s <= now:
            ep.step()
            steps += 1
            if steps >= MAX_CATCH_UP_STEPS and ep.next_step_s <= now:
                lag = now - ep.next_step_s
                self._t0 += lag / self.time_scale
                break

    def _run_guarded(self) -> None:
        try:
            self.run(self._stop)
        except BaseException as exc:  # reported by stop(); a test must not hang on it
            self.error = exc
            raise

    def start(self) -> MavsimServer:
        """Serve on a background thread."""
        if self._thread is not None:
            raise MavsimError("already started")
        self._thread = threading.Thread(target=self._run_guarded, name="mavsim", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop the background thread and close the sockets."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
            self._thread = None
        self.close()
        if self.error is not None:
            raise MavsimError(f"the simulator loop failed: {self.error!r}") from self.error

    def close(self) -> None:
        for ep in self.endpoints:
            ep.close()

    def __enter__(self) -> MavsimServer:
        return self.start()

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.stop()

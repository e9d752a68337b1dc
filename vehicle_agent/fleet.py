"""A fleet host: many simulated vehicles' agents in one process and one event loop.

Each vehicle keeps what makes it a vehicle on the bus: its own Zenoh session opened with its
own certificate (so its access-control rights, its liveliness token and its keys are exactly
those of a separate ``skyquill agent``), its own job runner, simulated backend, job lease, report
and event outboxes: an :class:`vehicle_agent.service.AgentService`, the same one an agent
process runs. What the host shares is what costs without being the vehicle's: the interpreter
and its imports, the Zenoh runtime (0.15 MiB a session), so an idle vehicle adds about 0.3 MiB
to the host against 71 MiB for an agent process (``benchmarks/bench_fleet_host.py``); one
:class:`vehicle_agent.pacer.SharedTicker` per control rate (one timer steps every awake vehicle
together) and a small :class:`vehicle_agent.work_pool.PlanPool` of planning workers.

The vehicles in flight also share their physics: a kind with a
:class:`vehicles.kind.SimulatedFleet` (the brush quadrotor) keeps them as rows of one simulated
world and controller, stepped once per shared tick for all of them
(:class:`vehicle_agent.backends.sim_round.StepRounds`), each flying exactly as it would alone;
on one vehicle the world and controller cost about 0.2 ms a tick, on fifty together about as
much in all. What stays per vehicle is its runner and service (reference, safety, trace,
telemetry, lease). Beyond what one core keeps in real time the vehicles all slow down together
(no tick is skipped), and past the show's ``lost_after_s`` of unacknowledged writing they give
their jobs up as any stalled agent would.

A vehicle's service that fails is started again, alone, after :data:`RESTART_DELAY_S` (its
session closed meanwhile, so the orchestrator sees that vehicle, and only it, leave and come
back), as the supervisor would restart its agent process. Real vehicles are never carried: an
autopilot link belongs on its vehicle's companion computer, one agent each.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Sequence

from bus.session import Session, open_session
from showfile import Show
from vehicle_agent.agent import make_backend, make_service
from vehicle_agent.backends.sim_round import StepRounds
from vehicle_agent.events import EventOutbox
from vehicle_agent.pacer import SharedTicker
from vehicle_agent.service import AgentService
from vehicle_agent.setup import VehicleSetup, vehicle_setup
from vehicle_agent.work_pool import PlanPool, pool_size

log = logging.getLogger(__name__)

RESTART_DELAY_S = 1.0
"""Wall time in [s] before a vehicle whose service failed is started again."""


class FleetError(ValueError):
    """The vehicles asked for cannot share a fleet host (one line, for the command line)."""


def check_fleet(show: Show, vehicle_ids: Sequence[str]) -> None:
    """Raise :class:`FleetError` unless ``vehicle_ids`` are distinct simulated vehicles of
    ``show`` (a real vehicle keeps one agent on its companion computer)."""
    if not vehicle_ids:
        raise FleetError("a fleet host needs at least one vehicle")
    known = {v.id: v for v in show.vehicles}
    seen: set[str] = set()
    for vehicle_id in vehicle_ids:
        if vehicle_id in seen:
            raise FleetError(f"vehicle {vehicle_id} is named twice")
        seen.add(vehicle_id)
        vehicle = known.get(vehicle_id)
        if vehicle is None:
            raise FleetError(f"no vehicle {vehicle_id!r} in show {show.show_id}")
        if vehicle.backend != "sim":
            raise FleetError(
                f"vehicle {vehicle_id} has backend {vehicle.backend}: a real vehicle keeps one "
                "agent on its companion computer (skyquill agent), never a fleet host"
            )


class FleetHost:
    """The agents of ``vehicle_ids`` in this event loop; ``await run(stop)`` until ``stop``."""

    def __init__(
        self,
        show: Show,
        vehicle_ids: Sequence[str],
        *,
        time_scale: float | None = None,
        seed: int = 0,
        workers: int | None = None,
    ) -> None:
        check_fleet(show, vehicle_ids)
        self.show = show
        self.setups = {v: vehicle_setup(show, v, time_scale=time_scale) for v in vehicle_ids}
        scale = next(iter(self.setups.values())).time_scale
        self.pool = PlanPool(show, scale, workers if workers is not None else pool_size())
        self.seed = seed
        self.rounds = StepRounds()
        """The simulated fleets of the host's vehicles in flight, one per kind and settings."""
        self.tickers: dict[float, SharedTicker] = {}
        """One shared ticker per wall period in [s] (vehicles of one kind share one)."""
        self.services: dict[str, AgentService] = {}
        """Each vehicle's running service (a new one after a restart)."""
        self.sessions: dict[str, Session] = {}
        """Each vehicle's open session (its own identity), while it is on the bus."""
        self.restarts = dict.fromkeys(vehicle_ids, 0)
        """How many times each vehicle's service was started again."""
        self._stops = {v: asyncio.Event() for v in vehicle_ids}
        self._numbers = {v: i for i, v in enumerate(vehicle_ids)}

    @property
    def vehicle_ids(self) -> list[str]:
        """The vehicles carried."""
        return list(self.setups)

    def stop_vehicle(self, vehicle_id: str) -> None:
        """Take one vehicle off the bus (its session closed: its token goes); the others fly on."""
        self._stops[vehicle_id].set()

    async def run(self, stop: asyncio.Event) -> None:
        """Open every vehicle's session, fly them until ``stop``, then close everything."""
        await self.pool.warm(self.vehicle_ids)  # before the vehicles join: no cold first job
        fleet = [asyncio.create_task(self._carry(v, stop)) for v in self.setups]
        try:
            await stop.wait()
        finally:
            for vehicle_stop in self._stops.values():
                vehicle_stop.set()
            await asyncio.gather(*fleet, return_exceptions=True)
            await self.pool.close()

    async def land_then_stop(self, stop: asyncio.Event, limit_s: float) -> None:
        """Land every vehicle in the air, all together, each as its own agent would
        (``vehicle_agent/stop_signals.py``); then set ``stop``."""
        services = list(self.services.values())
        await asyncio.gather(*(one.land_then_stop(asyncio.Event(), limit_s) for one in services))
        stop.set()

    async def _carry(self, vehicle_id: str, fleet_stop: asyncio.Event) -> None:
        """One vehicle: its service on its own session, started again when it fails."""
        setup, stop = self.setups[vehicle_id], self._stops[vehicle_id]
        while not (stop.is_set() or fleet_stop.is_set()):
            service = self._service(setup)
            try:
                session = await asyncio.to_thread(_open, service)
            except Exception:
                log.exception("%s: cannot join the bus", vehicle_id)
            else:
                self.sessions[vehicle_id] = session
                try:
                    await service.serve(session, stop)
                except Exception:
                    log.exception("%s: agent failed; starting it again", vehicle_id)
                finally:
                    del self.sessions[vehicle_id]
                    session.close()  # type: ignore[no-untyped-call]
            if stop.is_set():
                return
            self.restarts[vehicle_id] += 1
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(stop.wait(), RESTART_DELAY_S)

    def _service(self, setup: VehicleSetup) -> AgentService:
        events = EventOutbox(setup.vehicle_id)
        seed = self.seed + self._numbers[setup.vehicle_id]
        backend = make_backend(setup, seed=seed, on_text=events.autopilot_text, rounds=self.rounds)
        period_s = backend.control_period_s / setup.time_scale
        ticker = self.tickers.setdefault(period_s, SharedTicker(period_s))
        work = self.pool.for_vehicle(setup.vehicle_id)
        service = make_service(setup, backend, work, events, pacer=ticker)
        self.services[setup.vehicle_id] = service
        return service


def _open(service: AgentService) -> Session:
    """The vehicle's own session, with its own certificate (in a thread: opening blocks)."""
    return open_session(service.settings.zenoh, role="client")

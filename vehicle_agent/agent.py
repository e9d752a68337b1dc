"""One vehicle of a show as a process: its backend, its job runner and the agent service.

Pure apart from :func:`run_agent` (the process entry point used by ``skyquill agent``): the show
is read once by :func:`vehicle_agent.setup.vehicle_setup`; jobs are planned and measured in the
agent's planning worker (:mod:`vehicle_agent.plan_worker`, with :mod:`vehicle_agent.jobs`), so
this module imports neither the planner nor matplotlib.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable

from trust.settings import session_settings
from vehicle_agent.backends.base import VehicleBackend
from vehicle_agent.backends.sim import SimBackend, SimVehicle
from vehicle_agent.backends.sim_round import StepRounds
from vehicle_agent.events import EventOutbox
from vehicle_agent.job_runner import JobRunner
from vehicle_agent.pacer import Pacer
from vehicle_agent.rest import REST_PERIOD_S
from vehicle_agent.service import AgentService
from vehicle_agent.service_settings import ServiceSettings
from vehicle_agent.setup import VehicleSetup, on_board
from vehicle_agent.stop_signals import run_landing_first
from vehicle_agent.work import JobWork
from vehicle_agent.worker_client import ProcessJobWork


def make_backend(
    setup: VehicleSetup,
    *,
    seed: int = 0,
    on_text: Callable[[int, str], None] | None = None,
    rounds: StepRounds | None = None,
) -> VehicleBackend:
    """The backend the show file names for this vehicle; ``on_text(severity, text)`` hears what
    an autopilot says (MAVLink STATUSTEXT), e.g. ``EventOutbox.autopilot_text``. A simulated
    vehicle of a fleet host (``rounds``) flies in its kind's fleet, stepped with the others."""
    vehicle = setup.show.vehicle(setup.vehicle_id)
    if vehicle.backend == "sim":
        step_round = None if rounds is None else rounds.round_for(setup.kind, setup.settings)
        sim = SimVehicle(
            vehicle.home_m_enu,
            kind=setup.kind,
            settings=setup.settings,
            seed=seed,
            contact_region=on_board(setup),
            fleet=None if step_round is None else step_round.fleet,
        )
        return SimBackend(sim, step_round)
    from vehicle_agent.backends.mavlink.create import create_backend  # pymavlink: only here

    return create_backend(setup, on_text=on_text)


def make_runner(setup: VehicleSetup) -> JobRunner:
    """A fresh job runner for this vehicle."""
    return JobRunner(setup.runner_config)


def service_settings(setup: VehicleSetup) -> ServiceSettings:
    """How this vehicle's agent joins the bus (its own identity) and paces its loop."""
    simulated = setup.show.vehicle(setup.vehicle_id).backend == "sim"
    return ServiceSettings(
        show_id=setup.show.show_id,
        zenoh=session_settings(setup.show, setup.vehicle_id),
        time_scale=setup.time_scale,
        skip_when_late=not simulated,
        lost_after_s=setup.show.policy.lost_after_s,
        rest_period_s=REST_PERIOD_S if simulated else None,
        results_dir=setup.show.database_path.parent / "results" / setup.vehicle_id,
    )


def make_service(
    setup: VehicleSetup,
    backend: VehicleBackend,
    work: JobWork,
    events: EventOutbox | None = None,
    pacer: Pacer | None = None,
) -> AgentService:
    """This vehicle's agent service with a fresh job runner (an agent process's, or one of a
    fleet host's: the same service, only ``work`` and ``pacer`` are shared there)."""
    return AgentService(
        service_settings(setup), make_runner(setup), backend, work, events=events, pacer=pacer
    )


async def run_agent(
    setup: VehicleSetup, backend: VehicleBackend, events: EventOutbox | None = None
) -> None:
    """Run this vehicle's agent until SIGINT/SIGTERM (the ``skyquill agent`` process), landing
    first when it is in the air (``vehicle_agent/stop_signals.py``), its jobs planned and
    measured in a planning worker process; ``events``: the outbox the backend's ``on_text`` was
    given."""
    work = ProcessJobWork(setup.show, setup.vehicle_id, setup.time_scale)
    await work.warm()  # before the vehicle is on the bus: its first job plans as fast as any
    await run_landing_first(make_service(setup, backend, work, events))


def run_agent_blocking(
    setup: VehicleSetup, backend: VehicleBackend, events: EventOutbox | None = None
) -> None:
    """:func:`run_agent` in a fresh event loop."""
    asyncio.run(run_agent(setup, backend, events))

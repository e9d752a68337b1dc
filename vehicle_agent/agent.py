"""One vehicle of a show as a process: its backend, its job runner and the agent service.

Pure apart from :func:`run_agent` (the process entry point used by ``skyquill agent``):
:func:`vehicle_setup` (:mod:`vehicle_agent.setup`) reads the show once; :func:`prepare_job`
(:mod:`vehicle_agent.jobs`) turns an assignment into a planned reference on this vehicle's board
through its kind; :func:`job_metrics` measures a flown job.
"""

from __future__ import annotations

import asyncio
import importlib
import logging
from collections.abc import Callable

from bus.messages import JobAssignment
from trust.settings import session_settings
from vehicle_agent.backends.base import VehicleBackend
from vehicle_agent.backends.sim import SimBackend, SimVehicle
from vehicle_agent.job_picture import PictureWorker
from vehicle_agent.job_runner import JobRunner
from vehicle_agent.jobs import (
    archive_job,
    job_metrics,
    prepare_job,
    write_job_picture,
    write_job_report,
)
from vehicle_agent.service import (
    AgentService,
    EventOutbox,
    ServiceSettings,
    run_until_signalled,
)
from vehicle_agent.setup import VehicleSetup, on_board, vehicle_setup

__all__ = [
    "job_metrics",
    "make_backend",
    "prepare_job",
    "run_agent",
    "vehicle_setup",
    "write_job_picture",
    "write_job_report",
]

PICTURE_WAIT_S = 3.0
"""On shutdown, how long in [s] the agent waits for a job's report.png still being drawn."""


def make_backend(
    setup: VehicleSetup, *, seed: int = 0, on_text: Callable[[int, str], None] | None = None
) -> VehicleBackend:
    """The backend the show file names for this vehicle; ``on_text(severity, text)`` hears what
    an autopilot says (MAVLink STATUSTEXT), e.g. ``EventOutbox.autopilot_text``."""
    vehicle = setup.show.vehicle(setup.vehicle_id)
    if vehicle.backend == "sim":
        sim = SimVehicle(
            vehicle.home_m_enu,
            kind=setup.kind,
            settings=setup.settings,
            seed=seed,
            contact_region=on_board(setup),
        )
        return SimBackend(sim)
    mavlink = importlib.import_module("vehicle_agent.backends.mavlink")
    backend: VehicleBackend = mavlink.create_backend(setup, on_text=on_text)
    return backend


def make_runner(setup: VehicleSetup) -> JobRunner:
    """A fresh job runner for this vehicle."""
    return JobRunner(setup.runner_config)


def warm_up(setup: VehicleSetup) -> None:
    """Plan one character before joining the bus: the first plan imports and initialises the
    solvers while holding the interpreter lock, which stalled the agent's loop (and its status
    heartbeat, by which the orchestrator knows it is alive) for up to a second."""
    try:
        prepare_job(setup, JobAssignment(job_id="warm-up", text="一"))
    except Exception as exc:  # the real jobs will say what is wrong
        logging.getLogger(__name__).warning("%s: warm-up plan failed: %s", setup.vehicle_id, exc)


async def run_agent(
    setup: VehicleSetup, backend: VehicleBackend, events: EventOutbox | None = None
) -> None:
    """Run this vehicle's agent until SIGINT/SIGTERM (the ``skyquill agent`` process);
    ``events``: the outbox the backend's ``on_text`` was given."""
    vehicle = setup.show.vehicle(setup.vehicle_id)
    warm_up(setup)
    pictures = PictureWorker(setup.vehicle_id)
    settings = ServiceSettings(
        show_id=setup.show.show_id,
        zenoh=session_settings(setup.show, setup.vehicle_id),
        time_scale=setup.time_scale,
        skip_when_late=vehicle.backend != "sim",
        lost_after_s=setup.show.policy.lost_after_s,
    )
    service = AgentService(
        settings,
        make_runner(setup),
        backend,
        prepare=lambda assignment: prepare_job(setup, assignment),
        measure=lambda prepared, trace: job_metrics(setup, prepared, trace),
        archive=lambda prepared, trace, metrics: archive_job(
            setup, pictures, prepared, trace, metrics
        ),
        events=events,
    )
    await run_until_signalled(service)
    await asyncio.to_thread(pictures.wait, PICTURE_WAIT_S)


def run_agent_blocking(
    setup: VehicleSetup, backend: VehicleBackend, events: EventOutbox | None = None
) -> None:
    """:func:`run_agent` in a fresh event loop."""
    asyncio.run(run_agent(setup, backend, events))

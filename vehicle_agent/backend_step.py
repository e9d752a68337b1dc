"""One control period carried out on the backend, as the runner decided it
(``vehicle_agent/job_runner.py``, :class:`vehicle_agent.runner_io.TickActions`): the mode
command first (take-off, land, emergency stop), then ``backend.tick`` with the setpoint.

A take-off the vehicle refuses goes back to the runner; any other backend error becomes a fault
on the snapshot the runner sees at its next tick.
"""

from __future__ import annotations

import logging
from dataclasses import replace

from vehicle_agent.backends.base import (
    BackendError,
    CommandRefusedError,
    NotReadyError,
    Vec3,
    VehicleBackend,
    VehicleSnapshot,
)
from vehicle_agent.events import EventOutbox
from vehicle_agent.job_runner import JobRunner, TickActions

log = logging.getLogger(__name__)


async def step_backend(
    backend: VehicleBackend,
    runner: JobRunner,
    events: EventOutbox,
    actions: TickActions,
    snapshot: VehicleSnapshot,
    now_s: float,
) -> VehicleSnapshot:
    """The vehicle after ``actions`` at agent time ``now_s`` [s]; ``snapshot``: before them."""
    try:
        if actions.backend_command is not None:
            name, hover = actions.backend_command
            if name == "takeoff" and hover is not None:
                await _takeoff(backend, runner, events, hover, now_s)
            elif name == "land":
                await backend.land()
            elif name == "estop":
                await backend.estop()
        return await backend.tick(actions.setpoint, now_s)
    except BackendError as exc:
        log.error("%s: backend fault: %s", runner.config.vehicle_id, exc)
        return replace(snapshot, fault=str(exc))


async def _takeoff(
    backend: VehicleBackend, runner: JobRunner, events: EventOutbox, hover: Vec3, now_s: float
) -> None:
    """Take off; a refusal (pre-arm checks) hands the job back, any other error is a fault;
    a vehicle that was not asked (its checks had just begun failing) waits for them again."""
    vehicle_id = runner.config.vehicle_id
    try:
        await backend.takeoff(hover)
    except NotReadyError as exc:
        log.info("%s: not taking off yet: %s", vehicle_id, exc)
        runner.takeoff_refused(str(exc), now_s, not_ready=True)
    except CommandRefusedError as exc:
        job_id = runner.job_id
        log.warning("%s: take-off refused: %s", vehicle_id, exc)
        runner.takeoff_refused(str(exc), now_s)
        message = f"{vehicle_id} take-off refused: {exc}"
        events.push("warning", "takeoff_refused", message, job_id=job_id)

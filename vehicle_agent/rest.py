"""When a vehicle's control loop may rest (pure): nothing but safety needs it at the control rate.

A vehicle at rest is on the ground with its motors off and no job: nothing it does changes from
one control period to the next. Its agent then ticks only every ``rest_period_s`` (the runner
still sees faults, telemetry and status still go out), and wakes at once on a command, an
assignment or a change of the orchestrator's presence (``vehicle_agent.service``).
"""

from __future__ import annotations

from vehicle_agent.backends.base import VehicleSnapshot
from vehicle_agent.job_runner import JobRunner

REST_PERIOD_S = 1.0
"""Wall time in [s] between ticks of a simulated vehicle at rest (and its telemetry period)."""
RESTING_PHASES = ("ground", "stopped")
"""Runner phases in which the vehicle is on the ground by its own account."""
RESTING_MODES = ("idle", "estop")
"""Backend modes with the motors off."""


def at_rest(runner: JobRunner, snapshot: VehicleSnapshot) -> bool:
    """Whether the vehicle is landed, motors off, with no job and nothing commanded."""
    return (
        runner.job_id is None
        and runner.phase in RESTING_PHASES
        and snapshot.on_ground
        and snapshot.mode in RESTING_MODES
    )

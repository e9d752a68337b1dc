"""Leaving ``fault`` on the operator's ``clear_fault`` (pure): only a vehicle at rest may.

A vehicle ends in ``fault`` after an emergency stop, a fault its backend reported, or a landing
outside its geofence. The operator's ``clear_fault`` (forwarded by the orchestrator) brings it
back to ``landed`` only when its backend reports it safe: on the ground, motors disarmed, and no
fault any more. It then still takes no job while the operator holds it (``release``).
"""

from __future__ import annotations

from bus.messages import CommandReply
from vehicle_agent.backends.base import VehicleSnapshot
from vehicle_agent.job_runner import JobRunner
from vehicle_agent.runner_io import refuse


def unsafe_because(snapshot: VehicleSnapshot) -> str | None:
    """Why the vehicle may not leave ``fault`` (None: it may)."""
    if snapshot.fault is not None:
        return f"the vehicle still reports a fault: {snapshot.fault}"
    if not snapshot.on_ground:
        return "it is not on the ground"
    if snapshot.armed:
        return "its motors are armed"
    return None


def clear_fault(runner: JobRunner, snapshot: VehicleSnapshot) -> CommandReply:
    """Answer ``clear_fault``: the runner goes from ``fault`` to ``landed`` if it is safe."""
    vid = runner.config.vehicle_id
    if runner.state != "fault" or runner.phase != "stopped":
        return CommandReply(ok=True, message=f"{vid} is not in fault ({runner.state})")
    why = unsafe_because(snapshot)
    if why is not None:
        return refuse("unsafe", f"{vid} stays in fault: {why}")
    runner.state, runner.phase = "landed", "ground"
    runner.message = "fault cleared by the operator"
    return CommandReply(ok=True, message=f"{vid} fault cleared: landed, disarmed")

"""Leaving ``fault`` on the operator's ``clear_fault``: only a vehicle at rest may.

A vehicle ends in ``fault`` after an emergency stop, a fault its backend reported, or a landing
outside its geofence. The operator's ``clear_fault`` (forwarded by the orchestrator) brings it
back to ``landed`` only when it rests on the ground with its motors disarmed and its backend
agrees to leave ``estop`` or its fault (:meth:`VehicleBackend.recover`: the simulated vehicles
at once, an autopilot once its link is alive and it says it is disarmed on the ground). Its next
take-off then goes through every usual check (an autopilot re-arms through its pre-arm checks).
It still takes no job while the operator holds it (``release``).
"""

from __future__ import annotations

from bus.messages import CommandReply
from vehicle_agent.backends.base import BackendError, VehicleBackend, VehicleSnapshot
from vehicle_agent.job_runner import JobRunner
from vehicle_agent.runner_io import refuse


def unsafe_because(snapshot: VehicleSnapshot) -> str | None:
    """Why the vehicle may not leave ``fault`` as it is seen now (None: it may, if its backend
    agrees)."""
    if not snapshot.on_ground:
        return "it is not on the ground"
    if snapshot.armed:
        return "its motors are armed"
    return None


async def clear_fault(
    runner: JobRunner, snapshot: VehicleSnapshot, backend: VehicleBackend
) -> CommandReply:
    """Answer ``clear_fault``: the runner goes from ``fault`` to ``landed``, and the backend from
    ``estop`` (or its fault) to ``idle``, if both are safe."""
    vid = runner.config.vehicle_id
    if runner.state != "fault" or runner.phase != "stopped":
        return CommandReply(ok=True, message=f"{vid} is not in fault ({runner.state})")
    why = unsafe_because(snapshot)
    if why is not None:
        return refuse("unsafe", f"{vid} stays in fault: {why}")
    try:
        await backend.recover()
    except BackendError as exc:
        return refuse("unsafe", f"{vid} stays in fault: {exc}")
    if runner.state != "fault":  # a command came in while the backend answered
        return CommandReply(ok=True, message=f"{vid} is not in fault ({runner.state})")
    runner.state, runner.phase = "landed", "ground"
    runner.message = "fault cleared by the operator"
    return CommandReply(ok=True, message=f"{vid} fault cleared: landed, disarmed, ready to fly")

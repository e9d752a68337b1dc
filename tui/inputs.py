"""What the console's model takes in besides bus messages: presence changes and bad payloads."""

from __future__ import annotations

from dataclasses import dataclass

from bus.messages import Event, JobState, ShowSnapshot, Telemetry, VehicleStatus


@dataclass(frozen=True)
class VehiclePresence:
    """A vehicle's liveliness token appeared (alive) or vanished (lost)."""

    vehicle_id: str
    """Vehicle whose token changed."""
    alive: bool
    """True when the token exists."""


@dataclass(frozen=True)
class OrchestratorPresence:
    """The orchestrator's liveliness token appeared or vanished."""

    alive: bool
    """True when the token exists."""


@dataclass(frozen=True)
class BadPayload:
    """A sample that could not be decoded; shown in the event log, otherwise ignored."""

    key: str
    """Key expression it arrived on."""
    message: str
    """What was wrong with it."""


BusInput = (
    ShowSnapshot
    | JobState
    | Event
    | Telemetry
    | VehicleStatus
    | VehiclePresence
    | OrchestratorPresence
    | BadPayload
)
"""Everything :meth:`ConsoleModel.apply` accepts."""

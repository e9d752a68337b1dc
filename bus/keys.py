"""Every key expression of skyquill, in one place.

All keys live under ``skyquill/<show_id>/``; see docs/protocol.md for who publishes, who answers,
and which message each carries.
"""

from __future__ import annotations

from dataclasses import dataclass

ROOT = "skyquill"
PROTOCOL_VERSION = 1


def _check_chunk(value: str, what: str) -> str:
    if not value or any(c in value for c in "/*$?#"):
        raise ValueError(f"{what} {value!r} must be non-empty and contain none of / * $ ? #")
    return value


@dataclass(frozen=True)
class ShowKeys:
    """Key expressions of one show."""

    show_id: str
    """Show identifier from the show file; one Zenoh namespace per show."""

    def __post_init__(self) -> None:
        _check_chunk(self.show_id, "show_id")

    @property
    def prefix(self) -> str:
        return f"{ROOT}/{self.show_id}"

    # --- orchestrator -------------------------------------------------------------------------
    @property
    def submit(self) -> str:
        """Queryable (orchestrator): SubmitRequest -> SubmitReply from the show's own operator
        (identity ``operator``: the console and the CLI); access control lets only it query."""
        return f"{self.prefix}/orchestrator/submit"

    def submit_as(self, identity: str) -> str:
        """Queryable (orchestrator): SubmitRequest -> SubmitReply from ``identity`` (its
        certificate's common name); access control lets only that identity query it, so the
        orchestrator counts its quotas by the key, not by the self-declared ``client_id``."""
        return f"{self.submit}/{_check_chunk(identity, 'identity')}"

    @property
    def submits_all(self) -> str:
        """What the orchestrator declares to answer every identity's submissions."""
        return f"{self.submit}/*"

    @property
    def command(self) -> str:
        """Queryable (orchestrator): OperatorCommand -> CommandReply from the show's own
        operator (identity ``operator``: the console and the CLI)."""
        return f"{self.prefix}/orchestrator/command"

    def command_as(self, identity: str) -> str:
        """Queryable (orchestrator): OperatorCommand -> CommandReply from ``identity`` (an
        outside operator's certificate); access control lets only that identity query it, so
        the event log names who sent each command by the key, not by a self-declared name."""
        return f"{self.command}/{_check_chunk(identity, 'identity')}"

    @property
    def commands_all(self) -> str:
        """What the orchestrator declares to answer every outside operator's commands."""
        return f"{self.command}/*"

    def report(self, vehicle_id: str) -> str:
        """Queryable (orchestrator): AgentReport -> CommandReply from one vehicle's agent; the
        vehicle is the one in the key (access control lets only that agent query it)."""
        return f"{self.prefix}/orchestrator/report/{_check_chunk(vehicle_id, 'vehicle_id')}"

    @property
    def reports_all(self) -> str:
        """What the orchestrator declares to answer every vehicle's reports."""
        return f"{self.prefix}/orchestrator/report/*"

    @property
    def snapshot(self) -> str:
        """Queryable (orchestrator): empty query -> ShowSnapshot (late joiners start here)."""
        return f"{self.prefix}/orchestrator/snapshot"

    @property
    def clock(self) -> str:
        """Queryable (orchestrator): empty query -> ClockReply, its wall clock when the query
        came and when it replied; every vehicle's agent asks (``vehicle_agent/clock_sync.py``)."""
        return f"{self.prefix}/orchestrator/clock"

    @property
    def orchestrator_alive(self) -> str:
        """Liveliness token of the orchestrator."""
        return f"{self.prefix}/orchestrator/alive"

    def job(self, job_id: str) -> str:
        """Published (orchestrator) on every change of a job: JobState."""
        return f"{self.prefix}/jobs/{_check_chunk(job_id, 'job_id')}"

    @property
    def jobs_all(self) -> str:
        return f"{self.prefix}/jobs/*"

    @property
    def events(self) -> str:
        """Published (orchestrator): Event, the show's event log."""
        return f"{self.prefix}/events"

    @property
    def fleet(self) -> str:
        """Published (orchestrator) on change (every 0.1 s at most) and at 1 Hz: ShowSnapshot
        without finished jobs."""
        return f"{self.prefix}/fleet"

    # --- vehicles -----------------------------------------------------------------------------
    def vehicle_alive(self, vehicle_id: str) -> str:
        """Liveliness token of one vehicle agent."""
        return f"{self.prefix}/vehicles/{_check_chunk(vehicle_id, 'vehicle_id')}/alive"

    @property
    def vehicles_alive_all(self) -> str:
        return f"{self.prefix}/vehicles/*/alive"

    def telemetry(self, vehicle_id: str) -> str:
        """Published (agent) at 20 Hz: Telemetry. Subscribers should drop oldest."""
        return f"{self.prefix}/vehicles/{_check_chunk(vehicle_id, 'vehicle_id')}/telemetry"

    @property
    def telemetry_all(self) -> str:
        return f"{self.prefix}/vehicles/*/telemetry"

    def vehicle_status(self, vehicle_id: str) -> str:
        """Published (agent) on change and at 1 Hz: VehicleStatus."""
        return f"{self.prefix}/vehicles/{_check_chunk(vehicle_id, 'vehicle_id')}/status"

    @property
    def vehicle_status_all(self) -> str:
        return f"{self.prefix}/vehicles/*/status"

    def vehicle_events(self, vehicle_id: str) -> str:
        """Published (agent): Event about the vehicle (autopilot messages, refused take-offs);
        the orchestrator relays them into the show's ``events``."""
        return f"{self.prefix}/vehicles/{_check_chunk(vehicle_id, 'vehicle_id')}/events"

    @property
    def vehicle_events_all(self) -> str:
        return f"{self.prefix}/vehicles/*/events"

    def vehicle_command(self, vehicle_id: str) -> str:
        """Queryable (agent): VehicleCommand (``cancel``, ``land``, ``estop``, ``clear_fault``)
        -> CommandReply; the orchestrator and operators may query it."""
        return f"{self.prefix}/vehicles/{_check_chunk(vehicle_id, 'vehicle_id')}/command"

    def vehicle_assign(self, vehicle_id: str) -> str:
        """Queryable (agent): VehicleCommand ``assign`` -> CommandReply; only the orchestrator
        may query it."""
        return f"{self.prefix}/vehicles/{_check_chunk(vehicle_id, 'vehicle_id')}/assign"


def vehicle_id_from_key(key: str) -> str:
    """The vehicle id inside any ``.../vehicles/<id>/...`` key."""
    parts = key.split("/")
    try:
        return parts[parts.index("vehicles") + 1]
    except (ValueError, IndexError):
        raise ValueError(f"not a vehicle key: {key!r}") from None


def identity_under(base: str, key: str) -> str | None:
    """The identity of a ``<base>/<identity>`` key (``submit_as``, ``command_as``), or None if
    ``key`` is not one (a wildcard or anything else: only a literal key names who sent it)."""
    identity = key.removeprefix(base + "/")
    if identity == key or not identity or any(c in identity for c in "/*$?#"):
        return None
    return identity

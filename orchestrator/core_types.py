"""Policy and effects shared by the pure decision modules."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

from bus.messages import Event, VehicleCommand, WrittenInk
from orchestrator.fleet import EtaModel, VehicleInfo
from orchestrator.jobs import Job
from orchestrator.sheets import BoardSheets
from sim.battery import VehicleBattery


@dataclass(frozen=True)
class CoreConfig:
    """Policy of one show, from the show file."""

    show_id: str
    """Show id."""
    vehicles: tuple[VehicleInfo, ...]
    """Declared vehicles."""
    moderation: bool = False
    """Submissions wait for approval."""
    lost_after_s: float = 1.5
    """Grace after a liveliness token disappears before the vehicle is lost, [s]."""
    max_queue: int = 200
    """Most queued jobs (the operator's own submissions are never refused)."""
    max_awaiting: int = 100
    """Most jobs awaiting approval, counted apart from the queue (the operator's own
    submissions are never refused)."""
    max_attempts: int = 3
    """Assignments lost before the job fails."""
    max_handbacks: int = 10
    """Times a job may be taken back uncounted before it fails (nothing goes round for ever)."""
    confirm_grace_s: float = 3.0
    """How long a vehicle may not mention its assigned job before it is taken back, [s]."""
    lost_job_hold_s: float = 15.0
    """A job taken back from a lost vehicle that cannot have begun it waits this long for it;
    one that may have, this long past its write fence before the operator is told, [s]
    (``policy.lost_job_hold_s``, ``orchestrator/holders.py``)."""
    refuse_backoff_s: float = 2.0
    """No new assignment to a vehicle this long after it refused or did not answer, [s]."""
    tracking_error_alert_m: float = 0.05
    """Tracking error that raises an alert, [m]."""
    eta: EtaModel = field(default_factory=EtaModel)
    """ETA assumptions."""
    eta_tolerance_s: float = 2.0
    """A queued job whose expected start moved by more than this is published again, [s]."""
    boards: tuple[tuple[str, BoardSheets], ...] = ()
    """What a written character costs each board (default: ``when_spoiled``)."""
    sheet_change_s: float = 40.0
    """The crew's first expected turnaround for a sheet, show seconds (``policy``)."""
    batteries: tuple[tuple[str, VehicleBattery], ...] = ()
    """Each kind's battery (``vehicles/batteries.py``); a kind without one, or a vehicle that
    reports no charge, is dispatched without counting its battery."""
    battery_reserve_fraction: float = 0.20
    """Charge every job must leave in its vehicle (``battery.reserve_fraction``)."""
    battery_swap_s: float = 60.0
    """The crew's first expected turnaround for a battery swap, show seconds
    (``battery.swap_s``)."""
    clock_offset_max_s: float = 0.05
    """A vehicle's clock reported further than this from the orchestrator's raises an alert, [s]
    (``preflight.clock_offset_max_s``, ``orchestrator/clock_offsets.py``)."""


@dataclass
class Effects:
    """What the service must do after a decision."""

    jobs: dict[str, Job] = field(default_factory=dict)
    """Changed jobs (latest version): store, then publish."""
    moved: set[str] = field(default_factory=set)
    """Other queued jobs whose queue position or ETA changed: publish them again (no store)."""
    events: list[Event] = field(default_factory=list)
    """Event log lines to store and publish."""
    commands: list[tuple[str, VehicleCommand]] = field(default_factory=list)
    """(vehicle_id, command) to send to agents."""
    fleet_changed: bool = False
    """The fleet snapshot should be republished now."""
    settings_changed: bool = False
    """Queue pause or vehicle pauses changed (store them)."""
    written: dict[str, WrittenInk] = field(default_factory=dict)
    """Job id -> the ink picture of a job just done (kept out of ``jobs``): store it with the
    job, and send it on that job's ``jobs/<id>`` publication."""
    progressed: set[str] = field(default_factory=set)
    """Jobs in ``jobs`` whose only change is their progress: published, not stored (replaceable
    data, see ``store.py``; a restart shows the progress of their last stored change)."""

    @property
    def empty(self) -> bool:
        """Nothing to do (most heartbeats): the service skips storing and publishing."""
        return not (
            self.jobs
            or self.moved
            or self.events
            or self.commands
            or self.fleet_changed
            or self.settings_changed
            or self.written
        )


Level = Literal["info", "warning", "alert"]

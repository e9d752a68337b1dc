"""How an agent service joins the bus and paces its loop (from the show file, once)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from bus.session import ZenohSettings


@dataclass(frozen=True)
class ServiceSettings:
    """How the agent joins the bus and paces its loop."""

    show_id: str
    """Show id: the Zenoh namespace."""
    zenoh: ZenohSettings
    """Endpoints from the show file."""
    time_scale: float = 1.0
    """Agent seconds per wall second."""
    skip_when_late: bool = False
    """Real vehicles: jump ahead after a stall (see ``TickClock``)."""
    report_retry_s: float = 0.5
    """Wall time in [s] between attempts to deliver a report."""
    report_timeout_s: float = 2.0
    """Wall time in [s] to wait for the orchestrator's acknowledgement of one attempt."""
    status_period_s: float = 1.0
    """Wall time in [s] between status heartbeats at most (status is also sent on every change,
    and whenever the agent said nothing else for 1.1 ``lost_after_s / 3``)."""
    lost_after_s: float = 1.5
    """The show's ``policy.lost_after_s`` in [s]: the orchestrator takes a vehicle silent this
    long as lost; the heartbeat and the job lease follow from it."""
    rest_period_s: float | None = None
    """Wall time in [s] between ticks of a vehicle at rest (landed, no job, motors off); None:
    every control period, always (an autopilot needs its mocap and heartbeat streams)."""
    results_dir: Path | None = None
    """Where the results of written jobs wait for the orchestrator's answer, surviving a restart
    (``vehicle_agent/results.py``); None: in memory only."""
    clock_period_s: float = 10.0
    """Wall time in [s] between two measurements of the agent's clock against the
    orchestrator's after the start burst (``vehicle_agent/clock_sync.py``)."""

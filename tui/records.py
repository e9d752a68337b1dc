"""What the console keeps per vehicle and job, and the alerts they raise (pure)."""

from __future__ import annotations

from collections.abc import Iterable

import msgspec

from bus.messages import Event, JobState
from tui.rows import Alert, QueueRow, QueueSection
from tui.settings import ConsoleSettings
from tui.tracks import Track

AWAITING_JOB_STATES = frozenset({"awaiting_approval", "submitted"})
ACTIVE_JOB_STATES = frozenset({"assigned", "writing"})
FINAL_JOB_STATES = frozenset({"done", "failed", "cancelled", "rejected"})


def with_known_strokes(job: JobState, known: JobState | None) -> JobState:
    """``job``, keeping the strokes of an earlier version of it: the orchestrator sends a drawing's
    strokes only in some messages (``jobs/<id>`` while waiting), never in ``fleet``."""
    if job.strokes is None and known is not None and known.strokes is not None:
        return msgspec.structs.replace(job, strokes=known.strokes)
    return job


class VehicleRecord:
    """Mutable record behind a :class:`VehicleRow`."""

    def __init__(
        self, vehicle_id: str, kind: str = "", board_id: str | None = None, surface: str = ""
    ) -> None:
        self.vehicle_id = vehicle_id
        self.kind = kind
        self.board_id = board_id
        self.surface = surface
        self.state = "unknown"
        self.job_id: str | None = None
        self.progress = 0.0
        self.tracking_error_m: float | None = None
        self.battery_fraction: float | None = None
        self.battery_minutes_left: float | None = None
        self.preflight = ""
        """Why it may not take off now (its status's ``preflight``); empty: it may."""
        self.link_loss_fraction: float | None = None
        self.flight_s_today: float | None = None
        self.swap_note = ""
        """Why the orchestrator sent it for a battery swap (its summary's message); empty: it
        did not."""
        self.heard_s: float | None = None
        self.alive: bool | None = None
        self.message = ""
        self.position_m_enu: tuple[float, float, float] | None = None
        self.held = False
        self.paused = False
        self.force_n: float | None = None
        self.force_reference_n: float | None = None
        self.track = Track()


def over_threshold(v: VehicleRecord, settings: ConsoleSettings) -> bool:
    """Whether a present vehicle writes with a tracking error over the console's limit."""
    return (
        v.alive is not False
        and v.state == "writing"
        and v.tracking_error_m is not None
        and v.tracking_error_m > settings.tracking_error_alert_m
    )


def force_off(v: VehicleRecord, settings: ConsoleSettings) -> bool:
    """Whether a present vehicle writes with a contact force off its target by over the limit."""
    return (
        v.alive is not False
        and v.state == "writing"
        and v.force_n is not None
        and v.force_reference_n is not None
        and abs(v.force_n - v.force_reference_n) > settings.force_error_alert_n
    )


def current_alerts(
    orchestrator_offline: bool,
    vehicles: Iterable[VehicleRecord],
    jobs: Iterable[JobState],
    dirty_boards: Iterable[str],
    settings: ConsoleSettings,
    open_alerts: Iterable[Event] = (),
) -> list[Alert]:
    """Every alert raised now: the orchestrator gone, then each vehicle's (in ``vehicles``'
    order), then the boards' and jobs' (:func:`job_alerts`), then the orchestrator's open alerts
    of causes not said already (:func:`show_alert`)."""
    vehicles = list(vehicles)
    alerts: list[Alert] = []
    if orchestrator_offline:
        alerts.append(
            Alert(
                "orchestrator",
                "orchestrator_lost",
                "orchestrator gone: showing the last known state",
            )
        )
    limit_m = settings.tracking_error_alert_m
    for v in vehicles:
        alert = vehicle_alert(
            v, limit_m, over_threshold=over_threshold(v, settings), force_off=force_off(v, settings)
        )
        if alert is not None:
            alerts.append(alert)
    alerts.extend(job_alerts(jobs, dirty_boards))
    boards = {v.vehicle_id: v.board_id for v in vehicles}
    said = {a.key for a in alerts}
    for event in open_alerts:
        alert = show_alert(event, boards)
        if alert.key not in said:
            said.add(alert.key)
            alerts.append(alert)
    return alerts


def show_alert(event: Event, boards: dict[str, str | None]) -> Alert:
    """One of the orchestrator's open alerts (ShowSnapshot ``alerts``: it may have been raised
    while the console was away), keyed by its cause as the console's own alerts are."""
    vid = event.vehicle_id
    if event.kind == "vehicle_lost" and vid is not None:
        return Alert(f"lost:{vid}", "vehicle_lost", event.message)
    if event.kind == "vehicle_fault" and vid is not None:
        return Alert(f"fault:{vid}", "vehicle_fault", event.message)
    if event.kind in ("vehicle_held", "operator"):  # held by the orchestrator, or an estop
        return Alert(f"held:{vid or '*'}", "vehicle_held", event.message)
    board = boards.get(vid) if vid is not None else None
    if event.kind == "board_dirty" and board is not None:
        return Alert(f"sheet:{board}", "fresh_sheet", event.message)
    return Alert(f"show:{event.kind}:{vid}:{event.time_s}", "show_alert", event.message)


def vehicle_alert(
    v: VehicleRecord, limit_m: float, *, over_threshold: bool, force_off: bool = False
) -> Alert | None:
    """The one alert a vehicle raises now (lost before fault before tracking error before a
    contact force off its target before a battery swap), if any."""
    vid = v.vehicle_id
    if v.alive is False or v.state == "lost":
        return Alert(f"lost:{vid}", "vehicle_lost", f"{vid} lost")
    if v.state == "fault":
        why = f": {v.message}" if v.message else ""
        return Alert(f"fault:{vid}", "vehicle_fault", f"{vid} fault{why}")
    if over_threshold:
        error_cm = 100 * (v.tracking_error_m or 0.0)
        return Alert(
            f"tracking:{vid}",
            "tracking_error",
            f"{vid} tracking error {error_cm:.1f} cm > {100 * limit_m:.1f} cm",
        )
    if force_off:
        return Alert(
            f"force:{vid}",
            "force_error",
            f"{vid} force {v.force_n or 0.0:.1f} N, target {v.force_reference_n or 0.0:.1f} N",
        )
    if v.swap_note:
        return Alert(f"swap:{vid}", "battery_swap", f"{vid} {v.swap_note}; swap it, then b")
    return None


def job_alerts(jobs: Iterable[JobState], dirty_boards: Iterable[str]) -> list[Alert]:
    """Boards waiting for a fresh sheet, submissions waiting for approval, failed jobs."""
    alerts = [
        Alert(f"sheet:{b}", "fresh_sheet", f"{b} half-written: replace the sheet, then s")
        for b in sorted(dirty_boards)
    ]
    jobs = list(jobs)
    awaiting = [j for j in jobs if j.state in AWAITING_JOB_STATES]
    if awaiting:  # a newer submission brings an acknowledged alert back
        newest = max(awaiting, key=lambda j: (j.created_at_s, j.job_id))
        alerts.append(
            Alert(
                f"approval:{newest.job_id}",
                "awaiting_approval",
                f"{len(awaiting)} submission(s) awaiting approval",
            )
        )
    for job in jobs:
        if job.state == "failed":
            reason = job.error.message if job.error else "no reason given"
            alerts.append(
                Alert(
                    f"failed:{job.job_id}",
                    "job_failed",
                    f"job {job.job_id} ({job.label}) failed: {reason}",
                )
            )
    return alerts


def queue_rows(jobs_in: Iterable[JobState]) -> list[QueueRow]:
    """Awaiting approval, queued (in queue order), active, then done and failed (newest
    first)."""
    jobs = list(jobs_in)
    awaiting = sorted(
        (j for j in jobs if j.state in AWAITING_JOB_STATES),
        key=lambda j: j.created_at_s,
    )
    queued = sorted(
        (j for j in jobs if j.state == "queued"),
        key=lambda j: (j.queue_position or 10**9, -j.priority, j.created_at_s),
    )
    active = sorted(
        (j for j in jobs if j.state in ACTIVE_JOB_STATES), key=lambda j: j.vehicle_id or ""
    )
    done = sorted((j for j in jobs if j.state == "done"), key=lambda j: -j.updated_at_s)
    failed = sorted(
        (j for j in jobs if j.state in ("failed", "cancelled", "rejected")),
        key=lambda j: -j.updated_at_s,
    )
    sections: list[tuple[QueueSection, list[JobState]]] = [
        ("awaiting", awaiting),
        ("queued", queued),
        ("active", active),
        ("done", done),
        ("failed", failed),
    ]
    return [QueueRow(section, job) for section, group in sections for job in group]

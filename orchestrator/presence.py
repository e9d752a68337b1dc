"""Vehicle presence decisions (pure): liveliness, status, telemetry, and the passing of time.

A vehicle whose liveliness token has been gone for ``lost_after_s`` is lost and its job goes back
to the queue; a vehicle whose status has not mentioned the job it was given for
``confirm_grace_s`` gives it back too (it restarted, or refused silently). After an orchestrator
restart, jobs that were active wait for the same confirmation. Events the agents publish about
their vehicles (autopilot messages, refused take-offs) join the show's event log here.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from bus.messages import Event, VehicleStatus
from orchestrator.core_types import Effects

RELAY_BURST = 10.0
"""Events of one vehicle relayed at once before the rate limit applies."""
RELAY_RATE_PER_S = 1.0
"""Events of one vehicle relayed per second, sustained."""
MAX_KIND_CHARS = 40
MAX_MESSAGE_CHARS = 300

if TYPE_CHECKING:
    from orchestrator.core import Book


def liveliness(book: Book, vehicle_id: str, alive: bool, now_s: float) -> Effects:
    """A vehicle's token appeared or disappeared."""
    eff = Effects()
    view = book.vehicles.get(vehicle_id)
    if view is None:
        if alive:
            book.event(
                eff,
                now_s,
                "warning",
                "unknown_vehicle",
                f"{vehicle_id} is not in the show file",
                vehicle_id=vehicle_id,
            )
        return eff
    if alive == view.alive:
        return eff
    view.alive, view.last_seen_s = alive, now_s
    if alive:
        view.gone_since_s, view.was_seen, view.message = None, True, ""
        view.lost = False
        book.event(
            eff,
            now_s,
            "info",
            "vehicle_appeared",
            f"{vehicle_id} is here",
            vehicle_id=vehicle_id,
        )
    else:
        view.gone_since_s, view.message = now_s, "liveliness token gone"
    eff.fleet_changed = True
    tick_into(book, eff, now_s)
    return eff


def status(book: Book, status: VehicleStatus, now_s: float) -> Effects:
    """A vehicle's published status."""
    eff = Effects()
    view = book.vehicles.get(status.vehicle_id)
    if view is None:
        return eff
    changed = (view.state, view.reported_job_id) != (status.state, status.job_id)
    view.state, view.reported_job_id = status.state, status.job_id
    view.status_at_s = view.last_seen_s = now_s
    view.message = status.message
    job = book.active_job_of(status.vehicle_id)
    if job is not None and status.job_id != job.job_id:
        view.mismatch_since_s = view.mismatch_since_s or now_s
    else:
        view.mismatch_since_s = None
    eff.fleet_changed = changed
    tick_into(book, eff, now_s)
    return eff


def telemetry(
    book: Book, vehicle_id: str, tracking_error_m: float, job_id: str | None, now_s: float
) -> Effects:
    """A telemetry sample: liveness, and an alert (at most every 5 s) on large errors."""
    eff = Effects()
    view = book.vehicles.get(vehicle_id)
    if view is None:
        return eff
    view.last_seen_s = now_s
    limit = book.config.tracking_error_alert_m
    if tracking_error_m > limit and now_s - view.last_alert_s >= 5.0:
        view.last_alert_s = now_s
        book.event(
            eff,
            now_s,
            "alert",
            "limit",
            f"{vehicle_id} tracking error {tracking_error_m:.3f} m > {limit} m",
            vehicle_id=vehicle_id,
            job_id=job_id,
        )
    return eff


def vehicle_event(book: Book, vehicle_id: str, event: Event, now_s: float) -> Effects:
    """An event an agent published about its vehicle (``vehicles/<id>/events``), relayed into the
    show's log with the orchestrator's time; ``RELAY_BURST`` at once, then ``RELAY_RATE_PER_S``."""
    eff = Effects()
    view = book.vehicles.get(vehicle_id)
    if view is None:
        return eff
    since = view.event_tokens_at_s if view.event_tokens_at_s is not None else now_s
    view.event_tokens = min(RELAY_BURST, view.event_tokens + (now_s - since) * RELAY_RATE_PER_S)
    view.event_tokens_at_s = now_s
    if view.event_tokens < 1.0:
        return eff
    view.event_tokens -= 1.0
    book.event(
        eff,
        now_s,
        event.level,
        event.kind[:MAX_KIND_CHARS],
        event.message[:MAX_MESSAGE_CHARS],
        vehicle_id=vehicle_id,
        job_id=event.job_id,
    )
    return eff


def tick_into(book: Book, eff: Effects, now_s: float) -> None:
    """Lost vehicles give their job back; so do vehicles that do not confirm it; then assign."""
    for vid, view in book.vehicles.items():
        gone = view.gone_since_s
        if not view.alive and gone is not None and now_s - gone >= book.config.lost_after_s:
            if not view.lost:
                view.lost, view.reported_job_id = True, None
                eff.fleet_changed = True
                if view.was_seen:
                    book.event(
                        eff, now_s, "alert", "vehicle_lost", f"{vid} is lost", vehicle_id=vid
                    )
            job = book.active_job_of(vid)
            if job is not None:
                book.requeue(eff, job, now_s, f"{vid} was lost", lost=True)
        job = book.active_job_of(vid)
        if job is None or not view.alive or view.mismatch_since_s is None:
            continue
        since = max(view.mismatch_since_s, job.assigned_at_s or 0.0)
        if now_s - since >= book.config.confirm_grace_s:
            view.mismatch_since_s = None
            book.requeue(eff, job, now_s, f"{vid} is not writing it", lost=True)
    book.assign(eff, now_s)

"""Vehicle presence decisions (pure): liveliness, status, telemetry, and the passing of time.

A vehicle is present while its liveliness token is there *and* it speaks: its agent publishes its
status or its telemetry at least every 1.1 ``lost_after_s / 3`` (the heartbeat). A vehicle whose
token has been gone for ``lost_after_s``, or that has been silent for ``lost_after_s`` although its
token remains (a frozen process, a token held by someone else), is lost and its job goes back to the
queue; it is present again with its next status, and a job of its own that is still queued is its
own again if that status names it (it finished writing it meanwhile, or is writing it still). A
vehicle whose status has not mentioned the job it was given for ``confirm_grace_s`` gives it back
too (it refused silently, or gave it up on its lease under load): a hand-back that counts no
attempt, and the vehicle gets no job for ``refuse_backoff_s`` (``orchestrator/requeue.py``). At once
if its agent started anew since the job was given (its status's ``incarnation`` is new: it restarted
faster than it could be found lost, and its new self has no job): that counts, as a loss does (a
restart may be a crash). A vehicle that says it is in ``fault``, and one lost in the air that comes
back without its job, is held (``vehicle_held``, an alert naming why) until the operator releases
it: the hold is the orchestrator's and stored, so an agent restart, which forgets its fault, does
not shed it. Not for a token that went and came back: the orchestrator's own session
sees every token do that when it reconnects to the router (a router restart, or the orchestrator
frozen past its session's lease). After an orchestrator restart, jobs that were active wait for the
same confirmation. A vehicle whose status says its autopilot's pre-arm checks fail (``preflight``)
gets no job until a status says they pass: nothing is handed back, no back-off grows. Events the
agents publish about their vehicles (autopilot messages, refused take-offs) join the show's event
log here.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from bus.messages import AIRBORNE_STATES, Event, VehicleStatus
from orchestrator import battery_swaps, clock_offsets, holders
from orchestrator.core_types import Effects
from orchestrator.fleet import VehicleView
from orchestrator.requeue import hand_back, requeue

MAX_KIND_CHARS = 40
MAX_MESSAGE_CHARS = 300

if TYPE_CHECKING:
    from orchestrator.book_protocol import BookProtocol


def liveliness(book: BookProtocol, vehicle_id: str, alive: bool, now_s: float) -> Effects:
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
        view.gone_since_s, view.token_at_s = None, now_s
        _maybe_back(book, eff, view, now_s)
    else:
        view.gone_since_s, view.message = now_s, "liveliness token gone"
    eff.fleet_changed = True
    tick_into(book, eff, now_s)
    return eff


def status(book: BookProtocol, status: VehicleStatus, now_s: float) -> Effects:
    """A vehicle's published status: that vehicle checked, and jobs assigned if anything changed.
    Other vehicles are left to ``tick`` (the timer): sweeping the fleet on every heartbeat cost
    the orchestrator most of a core at 250 vehicles (``benchmarks/bench_heartbeat.py``)."""
    eff = Effects()
    view = book.vehicles.get(status.vehicle_id)
    if view is None:
        return eff
    was = (view.state, view.reported_job_id, view.preflight)
    changed = was != (status.state, status.job_id, status.preflight)
    view.state, view.reported_job_id = status.state, status.job_id
    view.preflight = status.preflight  # a vehicle whose checks pass may take a job at once
    view.status_at_s = view.last_seen_s = view.heard_at_s = now_s
    view.message = status.message
    view.battery_fraction = status.battery_fraction
    view.battery_minutes_left = status.battery_minutes_left
    view.link_loss_fraction, view.flight_s_today = status.link_loss_fraction, status.flight_s_today
    changed = battery_swaps.heard(book, eff, view) or changed
    clock_offsets.heard(book, eff, view, status.clock_offset_ms, now_s)
    if status.incarnation != view.incarnation:
        if view.incarnation is not None:
            view.restarted_at_s = now_s
        view.incarnation = status.incarnation
    changed = _maybe_back(book, eff, view, now_s) or changed
    if not view.lost:  # back from a loss with the job it had: writing it, or written
        named = book.jobs.get(status.job_id) if status.job_id is not None else None
        if named is not None:
            holders.reclaim(book, eff, named, view.info.vehicle_id, now_s)
        holders.heard_without(book, eff, view.info.vehicle_id, status.job_id, now_s)
        _hold_if_unsafe(book, eff, view, status, now_s)
    job = book.active_job_of(status.vehicle_id)
    if job is not None and status.job_id != job.job_id:
        view.mismatch_since_s = view.mismatch_since_s or now_s
        if _restarted_since(view, job.assigned_at_s):
            view.mismatch_since_s = None
            requeue(
                book, eff, job, now_s, f"{view.info.vehicle_id} restarted without it", lost=True
            )
    else:
        view.mismatch_since_s = None
    eff.fleet_changed = changed
    check_vehicle(book, eff, view, now_s)
    if changed or eff.jobs or eff.events:
        book.assign(eff, now_s)
    return eff


def _hold_if_unsafe(
    book: BookProtocol, eff: Effects, view: VehicleView, status: VehicleStatus, now_s: float
) -> None:
    """Hold a vehicle in ``fault``, or back from a loss in the air without a job of its own."""
    lost_in, view.lost_in_state = view.lost_in_state, None
    if view.held:
        return
    vid = view.info.vehicle_id
    if status.state == "fault":
        why = f"in fault ({status.message or 'no reason given'})"
    elif lost_in is not None and book.active_job_of(vid) is None:
        why = f"lost while {lost_in.replace('_', ' ')}, back without a job"
    else:
        return
    view.held = view.paused = True
    eff.settings_changed = eff.fleet_changed = True
    message = f"{vid} held: {why}; check it, then release it"
    book.event(eff, now_s, "alert", "vehicle_held", message, vehicle_id=vid)


def _restarted_since(view: VehicleView, assigned_at_s: float | None) -> bool:
    """Whether the vehicle's agent started anew after the job was given to it."""
    return (
        view.restarted_at_s is not None
        and assigned_at_s is not None
        and view.restarted_at_s > assigned_at_s
    )


def telemetry(
    book: BookProtocol,
    vehicle_id: str,
    tracking_error_m: float,
    job_id: str | None,
    now_s: float,
    *,
    writing: bool,
) -> Effects:
    """A telemetry sample: liveness, and an alert (at most every 5 s) on a large error while the
    vehicle writes, as the console's alert line does (``tui/records.py``). Not in transit: an
    autopilot's take-off ends within its tolerance of the hover point and its loop lags a move
    by 5-6 cm (ArduCopter and PX4 SITL, issue 31), an alert at every take-off that spoils no
    character; the agent's deviation bound aborts a runaway there."""
    eff = Effects()
    view = book.vehicles.get(vehicle_id)
    if view is None:
        return eff
    view.last_seen_s = view.heard_at_s = now_s
    limit = book.config.tracking_error_alert_m
    if writing and tracking_error_m > limit and now_s - view.last_alert_s >= 5.0:
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


def vehicle_event(book: BookProtocol, vehicle_id: str, event: Event, now_s: float) -> Effects:
    """An event an agent published about its vehicle (``vehicles/<id>/events``), relayed into the
    show's log with the orchestrator's time, at the rate :meth:`VehicleView.may_log` allows."""
    eff = Effects()
    view = book.vehicles.get(vehicle_id)
    if view is None:
        return eff
    if not view.may_log(now_s):
        return eff
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


def _maybe_back(book: BookProtocol, eff: Effects, view: VehicleView, now_s: float) -> bool:
    """A lost vehicle with its token that spoke within ``lost_after_s`` is present again."""
    heard = view.heard_at_s
    fresh = heard is not None and now_s - heard < book.config.lost_after_s
    if not (view.lost and view.alive and fresh):
        return False
    view.lost, view.was_seen = False, True
    vid = view.info.vehicle_id
    book.event(eff, now_s, "info", "vehicle_appeared", f"{vid} is here", vehicle_id=vid)
    eff.fleet_changed = True
    return True


def silent_for_s(view: VehicleView, now_s: float) -> float | None:
    """How long a vehicle with a token has said nothing, [s]: since its last status or telemetry,
    its token's appearance or the orchestrator's last stall, whichever is latest."""
    marks = [t for t in (view.heard_at_s, view.token_at_s, view.resumed_at_s) if t is not None]
    return now_s - max(marks) if marks else None


def router_link(book: BookProtocol, up: bool, now_s: float) -> Effects:
    """The orchestrator's own link to the router went (a router restart, a cut cable) or came
    back. Meanwhile nobody can be heard, so nobody is taken as lost for it; once it is back,
    every vehicle has ``lost_after_s`` from then to be heard again: the clients reconnect to
    a restarted router as the orchestrator does, and a router restart the supervisor repaired
    costs no vehicle (the loss was counted from the tokens' going, 0.3 s of a restart and more
    of a loaded machine's reconnection taken from the grace)."""
    eff = Effects()
    if not up:
        if book.router_down_since_s is None:
            book.router_down_since_s = now_s
            book.event(eff, now_s, "warning", "router_link", "the orchestrator lost the router")
        return eff
    since_s, book.router_down_since_s = book.router_down_since_s, None
    if since_s is None:
        return eff
    for view in book.vehicles.values():
        view.resumed_at_s = now_s
        if not view.alive and view.gone_since_s is not None:
            view.gone_since_s = max(view.gone_since_s, now_s)
    message = f"the orchestrator has the router again after {now_s - since_s:.1f} s"
    book.event(eff, now_s, "info", "router_link", message)
    return eff


def _why_lost(book: BookProtocol, view: VehicleView, now_s: float) -> str | None:
    """Why the vehicle is to be taken as lost now (None: it is not, or it cannot be heard: the
    orchestrator has no link to the router)."""
    if book.router_down_since_s is not None:
        return None
    lost_after = book.config.lost_after_s
    checked, view.checked_at_s = view.checked_at_s, now_s
    if checked is not None and now_s - checked > lost_after / 2:
        view.resumed_at_s = now_s  # we were not looking: wait for the queued heartbeats
    if not view.alive:
        gone = view.gone_since_s
        return "its token is gone" if gone is not None and now_s - gone >= lost_after else None
    silent = silent_for_s(view, now_s)
    if silent is not None and silent >= lost_after:
        return f"silent for {silent:.1f} s although its token remains"
    return None


def tick_into(book: BookProtocol, eff: Effects, now_s: float) -> None:
    """Lost vehicles give their job back; so do vehicles that do not confirm it; then assign."""
    for view in book.vehicles.values():
        check_vehicle(book, eff, view, now_s)
    holders.tell_overdue(book, eff, now_s)
    book.assign(eff, now_s)


def check_vehicle(book: BookProtocol, eff: Effects, view: VehicleView, now_s: float) -> None:
    """One vehicle lost gives its job back; so does one that did not confirm it in time."""
    vid = view.info.vehicle_id
    why = _why_lost(book, view, now_s)
    if why is not None:
        if not view.lost:
            if view.state in AIRBORNE_STATES and view.was_seen:
                view.lost_in_state = view.state
            view.lost, view.reported_job_id = True, None
            view.message = why
            eff.fleet_changed = True
            if view.was_seen:
                book.event(
                    eff, now_s, "alert", "vehicle_lost", f"{vid} is lost: {why}", vehicle_id=vid
                )
        job = book.active_job_of(vid)
        if job is not None:
            requeue(book, eff, job, now_s, f"{vid} was lost", lost=True, wait_for_holder=True)
    job = book.active_job_of(vid)
    if job is None or not view.alive or view.mismatch_since_s is None:
        return
    since = max(view.mismatch_since_s, job.assigned_at_s or 0.0)
    if now_s - since >= book.config.confirm_grace_s:
        view.mismatch_since_s = None
        view.refused_until_s = max(view.refused_until_s, now_s + book.config.refuse_backoff_s)
        hand_back(book, eff, job, now_s, f"{vid} is not writing it")

"""Operator commands applied to a :class:`~orchestrator.core.Book` (pure).

=============  ===========================================================================
approve        job awaiting approval -> queued; a character of a phrase: the whole phrase
reject         job awaiting approval -> rejected (``reason`` kept); a character of a phrase:
               the whole phrase, the reason on each; with ``job_ids`` or ``client_id`` many
               at once (``orchestrator/moderation.py``)
pause          no new assignments: the whole queue, or one vehicle (``vehicle_id``)
resume         undo pause: the queue and every vehicle not held, or one vehicle
release        a vehicle held by land / estop may take jobs again (``vehicle_id``)
release_all    every held vehicle may take jobs again (the queue stays as it is: ``resume``)
cancel         job -> cancelled; a vehicle writing it is told to stop; with ``job_ids`` or
               ``client_id`` every waiting one named (``orchestrator/moderation.py``)
land           vehicle lands and is held (no new job until ``release``); its job is requeued
               (one whose brush may have gone down waits for the vehicle's word first:
               it may have been written in full, ``orchestrator/holders.py``)
land_all       every vehicle lands and is held; the queue is paused; jobs go back to the queue
estop          motors off at once, vehicles held: one, or all (then the queue is paused too);
               the job goes back to the queue as with ``land`` (not failed: the character
               was not at fault)
clear_fault    ask a vehicle's agent to leave ``fault`` (``vehicle_id``); it does only when its
               backend reports it on the ground and disarmed; it stays held until ``release``
prioritize     set a waiting job's ``priority`` (higher first)
fresh_sheet    a half-written board (``board_id``) has a new sheet: jobs may be assigned there again
battery_       the crew put a fresh battery in a vehicle waiting for one (``vehicle_id``);
swapped        it takes jobs once its fresh pack reports (``orchestrator/battery_swaps.py``)
=============  ===========================================================================
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Literal

from bus.messages import CommandReply, ErrorInfo, OperatorCommand, VehicleCommand

if TYPE_CHECKING:
    from orchestrator.book_protocol import BookProtocol
    from orchestrator.core_types import Effects, Level
    from orchestrator.jobs import Job

from orchestrator import battery_swaps, holders
from orchestrator.jobs import transition, update
from orchestrator.moderation import apply_bulk, is_bulk, moderated_together
from orchestrator.requeue import requeue

DEFAULT_NAME = "operator"
"""``OperatorCommand.operator`` when the sender names no one."""
CREW = "crew"
"""The crew page's identity (the kiosk's second certificate, ``trust/acl.py``)."""
CREW_COMMANDS = ("fresh_sheet", "battery_swapped")
"""All the crew may send: a sheet changed, a battery swapped."""


def refused(identity: str, cmd: OperatorCommand) -> CommandReply | None:
    """Why ``identity`` may not send ``cmd`` (None: it may): the crew confirms sheets and
    batteries and nothing else, whatever its page or its process asks."""
    if identity != CREW or cmd.command in CREW_COMMANDS:
        return None
    allowed = " and ".join(CREW_COMMANDS)
    return _error("forbidden", f"the crew may send {allowed} only, not {cmd.command}", "command")


def signed_by(identity: str, declared: str) -> str:
    """Who the event log says sent a command: the certificate's identity (as the key it came
    on proves), and the name the sender declared beside it when that says more (the shared
    console's ``operator`` certificate, used by whoever sits at it: ``operator (ana)``)."""
    if declared in ("", DEFAULT_NAME, identity):
        return identity
    return f"{identity} ({declared})"


def _error(code: str, message: str, field: str | None = None) -> CommandReply:
    return CommandReply(
        ok=False, message=message, error=ErrorInfo(code=code, message=message, field=field)
    )


def _job(book: BookProtocol, cmd: OperatorCommand) -> Job | CommandReply:
    if cmd.job_id is None:
        return _error("missing_field", f"{cmd.command} needs job_id", "job_id")
    job = book.jobs.get(cmd.job_id)
    if job is None:
        return _error("unknown_job", f"no job {cmd.job_id}", "job_id")
    return job


def _vehicle_ok(book: BookProtocol, cmd: OperatorCommand, required: bool) -> CommandReply | None:
    if cmd.vehicle_id is None:
        return (
            _error("missing_field", f"{cmd.command} needs vehicle_id", "vehicle_id")
            if required
            else None
        )
    if cmd.vehicle_id not in book.vehicles:
        return _error(
            "unknown_vehicle",
            f"no vehicle {cmd.vehicle_id}; vehicles: {sorted(book.vehicles)}",
            "vehicle_id",
        )
    return None


def _stop_vehicles(
    book: BookProtocol,
    cmd: OperatorCommand,
    eff: Effects,
    now_s: float,
    order: Literal["land", "estop"],
) -> list[str]:
    everyone = cmd.command == "land_all" or cmd.vehicle_id is None
    vids = list(book.vehicle_ids(None if everyone else cmd.vehicle_id))
    for vid in vids:
        book.vehicles[vid].paused = book.vehicles[vid].held = True
        eff.commands.append((vid, VehicleCommand(command=order)))
        job = book.active_job_of(vid)
        if job is not None:  # begun, it may be written in full: it waits for the vehicle's word
            begun = job.writing_since_s is not None
            why = f"{vid}: operator {cmd.command}"
            requeue(book, eff, job, now_s, why, lost=False, wait_for_holder=begun)
    eff.settings_changed = eff.fleet_changed = True
    return vids


def _moderate(book: BookProtocol, cmd: OperatorCommand, eff: Effects, now_s: float) -> CommandReply:
    job = _job(book, cmd)
    if isinstance(job, CommandReply):
        return job
    if job.state != "awaiting_approval":
        return _error("bad_state", f"{job.job_id} is {job.state}, not awaiting approval", "job_id")
    message = cmd.reason or "rejected by the operator"
    info = ErrorInfo(code="rejected", message=message, reason=cmd.reason or None)
    together = moderated_together(book, job)
    for one in together:
        if cmd.command == "approve":
            book.put(eff, transition(one, "queued", now_s))
        else:
            book.put(eff, transition(one, "rejected", now_s, error=info))
    done = "approved" if cmd.command == "approve" else "rejected"
    return CommandReply(ok=True, message=f"{_what(job, together)} {done}")


def _what(job: Job, together: list[Job]) -> str:
    """The moderated job, or its phrase: ``phrase 新年快乐 (4 characters, p0)``."""
    if job.phrase is None:
        return job.job_id
    text = "".join(j.label for j in together)
    return f"phrase {text} ({len(together)} characters, {job.phrase.phrase_id})"


def _cancel(book: BookProtocol, cmd: OperatorCommand, eff: Effects, now_s: float) -> CommandReply:
    job = _job(book, cmd)
    if isinstance(job, CommandReply):
        return job
    if job.final:
        return _error("bad_state", f"{job.job_id} is already {job.state}", "job_id")
    if job.active and job.vehicle_id is not None:
        eff.commands.append((job.vehicle_id, VehicleCommand(command="cancel", job_id=job.job_id)))
    message = cmd.reason or f"cancelled by {cmd.operator}"
    info = ErrorInfo(code="cancelled", message=message, reason=cmd.reason or None)
    book.put(eff, transition(job, "cancelled", now_s, error=info))
    eff.fleet_changed = True
    return CommandReply(ok=True, message=f"{job.job_id} cancelled")


def _prioritize(
    book: BookProtocol, cmd: OperatorCommand, eff: Effects, now_s: float
) -> CommandReply:
    job = _job(book, cmd)
    if isinstance(job, CommandReply):
        return job
    if cmd.priority is None:
        return _error("missing_field", "prioritize needs priority", "priority")
    if job.state not in ("awaiting_approval", "queued"):
        return _error("bad_state", f"{job.job_id} is {job.state}; only waiting jobs", "job_id")
    book.put(eff, update(job, now_s, priority=cmd.priority))
    return CommandReply(ok=True, message=f"{job.job_id} priority {cmd.priority}")


def _pause_resume(book: BookProtocol, cmd: OperatorCommand, eff: Effects) -> CommandReply:
    paused = cmd.command == "pause"
    if cmd.vehicle_id is not None:
        view = book.vehicles[cmd.vehicle_id]
        view.paused = paused or view.held
        what = cmd.vehicle_id
    else:
        book.queue_paused = paused
        if not paused:
            for view in book.vehicles.values():
                view.paused = view.held
        what = "queue"
    eff.settings_changed = eff.fleet_changed = True
    held = sorted(v for v, view in book.vehicles.items() if view.held and what in ("queue", v))
    note = f" ({', '.join(held)} held: release to fly)" if held and not paused else ""
    return CommandReply(ok=True, message=f"{what} {'paused' if paused else 'resumed'}{note}")


def _release(book: BookProtocol, cmd: OperatorCommand, eff: Effects) -> CommandReply:
    """The only way out of a hold: one vehicle, named."""
    assert cmd.vehicle_id is not None  # checked by _vehicle_ok
    view = book.vehicles[cmd.vehicle_id]
    if not view.held:
        return _error("bad_state", f"{cmd.vehicle_id} is not held", "vehicle_id")
    view.held = view.paused = False
    eff.settings_changed = eff.fleet_changed = True
    return CommandReply(ok=True, message=f"{cmd.vehicle_id} released")


def _release_all(book: BookProtocol, eff: Effects) -> CommandReply:
    """Every held vehicle may take jobs again (after an e-stop or a land of the whole fleet)."""
    held = sorted(vid for vid, view in book.vehicles.items() if view.held)
    if not held:
        return _error("bad_state", "no vehicle is held", "vehicle_id")
    for vid in held:
        book.vehicles[vid].held = book.vehicles[vid].paused = False
    eff.settings_changed = eff.fleet_changed = True
    note = " (the queue is still paused: resume to fly)" if book.queue_paused else ""
    return CommandReply(ok=True, message=f"released {', '.join(held)}{note}")


def _clear_fault(book: BookProtocol, cmd: OperatorCommand, eff: Effects) -> CommandReply:
    """Forward to the agent, which alone knows whether its vehicle is safe (it answers in the
    event log: ``fault_cleared``, or ``fault_kept`` with the reason)."""
    assert cmd.vehicle_id is not None  # checked by _vehicle_ok
    eff.commands.append((cmd.vehicle_id, VehicleCommand(command="clear_fault")))
    return CommandReply(
        ok=True,
        message=f"{cmd.vehicle_id}: clear_fault sent (cleared only if landed and disarmed)",
    )


def _fresh_sheet(
    book: BookProtocol, cmd: OperatorCommand, eff: Effects, now_s: float
) -> CommandReply:
    """A board waiting for a sheet has one: half-written, or with a character the crew takes
    away (``orchestrator/sheets.py``); a job overdue for its lost holder there is free
    (``orchestrator/holders.py``)."""
    boards = sorted({view.info.board_id for view in book.vehicles.values()})
    if cmd.board_id is None:
        return _error("missing_field", "fresh_sheet needs board_id", "board_id")
    if cmd.board_id not in boards:
        return _error("unknown_board", f"no board {cmd.board_id}; boards: {boards}", "board_id")
    freed = holders.free_on_fresh_sheet(book, eff, cmd.board_id, now_s)
    taken_away = book.sheets.changed(cmd.board_id, now_s)
    if cmd.board_id not in book.dirty_boards and freed is None and not taken_away:
        return _error("bad_state", f"{cmd.board_id} is not waiting for a fresh sheet", "board_id")
    book.dirty_boards.discard(cmd.board_id)
    eff.settings_changed = eff.fleet_changed = True
    return CommandReply(ok=True, message=f"{cmd.board_id}: fresh sheet")


def apply_operator(book: BookProtocol, command: object, eff: Effects, now_s: float) -> CommandReply:
    """Carry out one operator command; the reply says what happened or what was wrong."""
    if not isinstance(command, OperatorCommand):
        return _error("invalid", "not an operator command")
    cmd = command
    needs_vehicle = cmd.command in ("land", "release", "clear_fault", "battery_swapped")
    if bad := _vehicle_ok(book, cmd, needs_vehicle):
        return bad
    if is_bulk(cmd):
        if cmd.command in ("reject", "cancel"):
            return apply_bulk(book, cmd, eff, now_s)  # an event line per job
        return _error("invalid", "job_ids and client_id go with reject or cancel only", "job_ids")
    if cmd.command in ("approve", "reject"):
        reply = _moderate(book, cmd, eff, now_s)
    elif cmd.command == "cancel":
        reply = _cancel(book, cmd, eff, now_s)
    elif cmd.command == "prioritize":
        reply = _prioritize(book, cmd, eff, now_s)
    elif cmd.command in ("pause", "resume"):
        reply = _pause_resume(book, cmd, eff)
    elif cmd.command == "release":
        reply = _release(book, cmd, eff)
    elif cmd.command == "release_all":
        reply = _release_all(book, eff)
    elif cmd.command == "clear_fault":
        reply = _clear_fault(book, cmd, eff)
    elif cmd.command == "fresh_sheet":
        reply = _fresh_sheet(book, cmd, eff, now_s)
    elif cmd.command == "battery_swapped":
        reply = battery_swaps.swapped(book, cmd, eff, now_s)
    elif cmd.command in ("land", "land_all"):
        vids = _stop_vehicles(book, cmd, eff, now_s, "land")
        if cmd.command == "land_all":
            book.queue_paused = True
        reply = CommandReply(ok=True, message=f"landing {', '.join(vids)}")
    else:  # estop
        vids = _stop_vehicles(book, cmd, eff, now_s, "estop")
        if cmd.vehicle_id is None:
            book.queue_paused = True
        reply = CommandReply(ok=True, message=f"emergency stop {', '.join(vids)}")
    if reply.ok:
        level: Level = "alert" if cmd.command == "estop" else "info"
        target = cmd.job_id or cmd.vehicle_id or cmd.board_id or ""
        if cmd.command == "prioritize":  # the new value, for the record
            target += f" to {cmd.priority}"
        phrase = book.jobs[cmd.job_id].phrase if cmd.job_id in book.jobs else None
        if cmd.command in ("approve", "reject") and phrase is not None:  # the whole phrase
            target += f" (phrase {phrase.phrase_id}, {phrase.size} characters)"
        book.event(
            eff,
            now_s,
            level,
            "operator",
            f"{cmd.operator}: {cmd.command} {target}".rstrip()
            + (f" ({cmd.reason})" if cmd.reason else ""),
            vehicle_id=cmd.vehicle_id,
            job_id=cmd.job_id,
        )
    return reply

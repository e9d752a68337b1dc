"""What a command key does, decided from what the operator sees (pure: no Textual, no Zenoh).

Each ``*_request`` function returns the command to send at once, an :class:`Ask` (a question to
confirm first) or a :class:`Refusal` (a one-line reason shown to the operator, nothing sent).
The question and the refusal name their target with :func:`~tui.safe_text.clean` text only.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

from bus.messages import MAX_BULK_JOBS, MAX_PRIORITY, JobState, OperatorCommand
from tui.records import ACTIVE_JOB_STATES, AWAITING_JOB_STATES, FINAL_JOB_STATES
from tui.rows import VehicleRow
from tui.safe_text import clean


@dataclass(frozen=True)
class Ask:
    """A command sent only once the operator confirms ``question``."""

    question: str
    label: str
    """Text of the confirm button."""
    commands: tuple[OperatorCommand, ...]
    """Sent in order once confirmed; none: the answer only decides what the console does."""
    reason_prompt: str | None = None
    """When set, the dialog has an input for an optional ``reason`` (sent with the command)."""


@dataclass(frozen=True)
class Refusal:
    """Nothing is sent; ``message`` says why (shown as a warning)."""

    message: str


Request = OperatorCommand | Ask | Refusal


def _name(identifier: str) -> str:
    return clean(identifier, 40)


def job_request(command: str, job: JobState | None, phrase: Sequence[JobState] = ()) -> Request:
    """``approve``, ``reject``, ``cancel``, ``raise`` or ``lower`` on the selected job;
    ``phrase``: the characters of its phrase the console knows, in reading order."""
    if job is None:
        return Refusal(f"{command}: no job selected (Tab to the queue, arrows to pick one)")
    what = f"{_name(job.job_id)} ({_name(job.label)})"
    if command in ("approve", "reject") and job.state not in AWAITING_JOB_STATES:
        return Refusal(f"{command}: {what} is {job.state}, not awaiting approval")
    if command in ("approve", "reject") and job.phrase is not None:
        return _moderate_phrase(command, job, phrase)
    if command == "approve":
        return OperatorCommand(command="approve", job_id=job.job_id)
    if command == "reject":
        return Ask(
            f"Reject {what}?\nThe visitor's submission will not be written.",
            "Reject",
            (OperatorCommand(command="reject", job_id=job.job_id),),
            reason_prompt="reason (optional, shown to the visitor)",
        )
    if command == "cancel":
        if job.state in FINAL_JOB_STATES:
            return Refusal(f"cancel: {what} is already {job.state}")
        return Ask(
            f"Cancel {what}?\n{_cancel_outcome(job, phrase)}",
            "Cancel job",
            (OperatorCommand(command="cancel", job_id=job.job_id),),
            reason_prompt="reason (optional, shown to the visitor)",
        )
    return _prioritize(command, job, what)


def _cancel_outcome(job: JobState, phrase: Sequence[JobState]) -> str:
    """What a cancel does to ``job`` and tells its visitor (``orchestrator/operator.py``: the
    vehicle is told to cancel, and returns and lands; the kiosk shows the reason;
    ``orchestrator/phrases.py``: a phrase that has not begun ends whole)."""
    told = "The visitor's ticket says the operator cancelled it, with your reason if you give one."
    if job.phrase is not None and not any(_began(j) for j in (job, *phrase)):
        return (
            f"Its phrase has not begun: all {job.phrase.size} characters are cancelled (a phrase"
            f" is written whole or not at all), their drones land.\n{told}"
        )
    others = " The other characters of its phrase go on." if job.phrase is not None else ""
    if job.state == "writing":
        return (
            "The vehicle writing it lifts its pen, returns and lands; what it wrote stays on the"
            f" board, unfinished, and is not written again.{others}\n{told}"
        )
    if job.state in ACTIVE_JOB_STATES:
        return f"Its vehicle returns and lands before writing it.{others}\n{told}"
    return f"It leaves the queue and will not be written.{others}\n{told}"


def _began(job: JobState) -> bool:
    """Whether a character's drone began writing it (as ``orchestrator/phrases.py`` counts)."""
    return job.state in ("writing", "done") or job.progress > 0


def _moderate_phrase(command: str, job: JobState, phrase: Sequence[JobState]) -> Ask:
    """A character of a phrase: the orchestrator approves or rejects the whole phrase (it is
    moderated as one submission), and the question says so before anything is sent."""
    assert job.phrase is not None
    size = job.phrase.size
    text = "".join(j.label for j in phrase) if len(phrase) == size else job.label
    what = f"the phrase {_name(text)} ({size} characters, {_name(job.phrase.phrase_id)})"
    verb: Literal["approve", "reject"] = "approve" if command == "approve" else "reject"
    send = (OperatorCommand(command=verb, job_id=job.job_id),)
    if verb == "approve":
        return Ask(
            f"Approve {what}?\nA phrase is one submission: all {size} characters are approved"
            " and written together.",
            "Approve phrase",
            send,
        )
    return Ask(
        f"Reject {what}?\nA phrase is one submission: all {size} characters are rejected, and"
        " the reason goes to every one.",
        "Reject phrase",
        send,
        reason_prompt="reason (optional, shown to the visitor)",
    )


def bulk_request(marked: list[JobState]) -> Request:
    """``R``: the marked jobs, awaiting approval ones rejected and queued ones cancelled, after one
    question naming how many and whose (a job a vehicle has is never marked)."""
    awaiting = [j.job_id for j in marked if j.state in AWAITING_JOB_STATES]
    queued = [j.job_id for j in marked if j.state == "queued"]
    if not awaiting and not queued:
        return Refusal("reject marked: no waiting job marked (space marks one, M a client's)")
    clients = sorted({j.client_id for j in marked})
    whose = ", ".join(_name(c) for c in clients[:3]) + (" …" if len(clients) > 3 else "")
    what = [f"{len(awaiting)} awaiting approval are rejected"] if awaiting else []
    what += [f"{len(queued)} queued are cancelled"] if queued else []
    commands = [
        OperatorCommand(command="reject", job_ids=awaiting[i : i + MAX_BULK_JOBS])
        for i in range(0, len(awaiting), MAX_BULK_JOBS)
    ] + [
        OperatorCommand(command="cancel", job_ids=queued[i : i + MAX_BULK_JOBS])
        for i in range(0, len(queued), MAX_BULK_JOBS)
    ]
    return Ask(
        f"Reject {len(awaiting) + len(queued)} marked job(s) from {whose}?\n"
        f"{' and '.join(what)}; none of them will be written.",
        "Reject marked",
        tuple(commands),
        reason_prompt="reason (optional, shown to the visitors)",
    )


def _prioritize(command: str, job: JobState, what: str) -> Request:
    if job.state not in ("awaiting_approval", "queued"):
        return Refusal(f"priority: {what} is {job.state}; only waiting jobs can move")
    step = 1 if command == "raise" else -1
    priority = max(-MAX_PRIORITY, min(MAX_PRIORITY, job.priority + step))
    if priority == job.priority:
        return Refusal(f"priority: {what} is already at {priority}")
    return OperatorCommand(command="prioritize", job_id=job.job_id, priority=priority)


def vehicle_request(command: str, row: VehicleRow | None) -> Request:
    """``land``, ``release``, ``clear_fault``, ``pause`` (pause or resume: a toggle) or
    ``battery_swapped`` on the selected vehicle."""
    if row is None:
        return Refusal(f"{command}: no vehicle selected")
    name = _name(row.vehicle_id)
    if command == "pause" and not row.paused:  # no new job: nothing moves, nothing to confirm
        return OperatorCommand(command="pause", vehicle_id=row.vehicle_id)
    if command == "pause":
        return Ask(
            f"Resume {name}?\nIt may take the next job and fly.",
            "Resume",
            (OperatorCommand(command="resume", vehicle_id=row.vehicle_id),),
        )
    if command == "land":
        return Ask(
            f"Land {name}?\nIt stays on the ground (held) until you release it with u.",
            "Land",
            (OperatorCommand(command="land", vehicle_id=row.vehicle_id),),
        )
    if command == "release":
        if not row.held:
            return Refusal(f"release: {name} is not held")
        return Ask(
            f"Release {name}?\nIt may take the next job and fly.",
            "Release",
            (OperatorCommand(command="release", vehicle_id=row.vehicle_id),),
        )
    if command == "battery_swapped":
        return _battery_swapped(row, name)
    if row.state != "fault":
        return Refusal(f"reset: {name} is {row.state}, not in fault")
    return Ask(
        f"Reset the fault of {name}?\nCheck the vehicle first. It stays held until released (u).",
        "Reset fault",
        (clear_fault(row.vehicle_id),),
    )


def _battery_swapped(row: VehicleRow, name: str) -> Request:
    if row.state != "battery_swap":
        return Refusal(f"battery: {name} is not waiting for a battery swap")
    return Ask(
        f"Battery swapped on {name}?\nSay yes once its fresh battery is in: it takes jobs "
        "again when the battery reports.",
        "Swapped",
        (OperatorCommand(command="battery_swapped", vehicle_id=row.vehicle_id),),
    )


def fresh_sheet_request(row: VehicleRow | None, dirty_boards: frozenset[str]) -> Request:
    """``fresh_sheet`` of the selected vehicle's board, once it waits for one (half-written,
    or its lost vehicle's job waits for it: ``orchestrator/holders.py``)."""
    board_id = row.board_id if row else None
    if board_id is None or board_id not in dirty_boards:
        waiting = ", ".join(_name(b) for b in sorted(dirty_boards)) or "none"
        return Refusal(f"fresh sheet: select a vehicle of a board waiting for one ({waiting})")
    return Ask(
        f"Fresh sheet on {_name(board_id)}?\nSay yes once its sheet is replaced: "
        "the next job is written there.",
        "Fresh sheet",
        (OperatorCommand(command="fresh_sheet", board_id=board_id),),
    )


def clear_fault(vehicle_id: str) -> OperatorCommand:
    return OperatorCommand(command="clear_fault", vehicle_id=vehicle_id)


def clear_all_request(fault_ids: list[str]) -> Request:
    if not fault_ids:
        return Refusal("reset: no vehicle in fault")
    names = ", ".join(_name(v) for v in fault_ids[:6]) + (" …" if len(fault_ids) > 6 else "")
    return Ask(
        f"Reset the fault of {len(fault_ids)} vehicle(s)?\n{names}\n"
        "Check them first. They stay held until released (u).",
        "Reset all",
        tuple(clear_fault(vid) for vid in fault_ids),
    )


def release_all_request(held_ids: list[str], queue_paused: bool) -> Request:
    """``U``: every held vehicle may fly again (after land all or E-STOP of all)."""
    if not held_ids:
        return Refusal("release all: no vehicle is held")
    names = ", ".join(_name(v) for v in held_ids[:6]) + (" …" if len(held_ids) > 6 else "")
    after = "\nThe queue stays paused: resume it with p." if queue_paused else ""
    return Ask(
        f"Release {len(held_ids)} held vehicle(s)?\n{names}\nThey may take jobs again.{after}",
        "Release all",
        (OperatorCommand(command="release_all"),),
    )


LAND_ALL = Ask(
    "Land ALL vehicles now?\nThey stay held until released (u, or U for all).",
    "Land all",
    (OperatorCommand(command="land_all"),),
)


def estop_ask(vehicle_id: str | None) -> Ask:
    """Emergency stop of one vehicle, or of all (None)."""
    if vehicle_id is None:
        question = "EMERGENCY STOP every vehicle?\nMotors stop: vehicles in the air will fall."
    else:
        question = f"EMERGENCY STOP {_name(vehicle_id)}?\nIts motors stop: in the air it will fall."
    command = OperatorCommand(command="estop", vehicle_id=vehicle_id, reason="operator")
    return Ask(question, "E-STOP", (command,))


def quit_request(airborne: int) -> Ask | None:
    """None: quit at once; else ask (the show keeps running either way)."""
    if airborne == 0:
        return None
    return Ask(
        f"{airborne} vehicle(s) are flying: quit the console?\nThe show keeps running.",
        "Quit console",
        (),
    )

"""How the page sees a phrase: one ticket, the state of each of its characters (pure).

A phrase handed in at the kiosk is one job per character on the bus (``JobState.phrase``: the
phrase's id is its first character's job id; ``orchestrator/phrases.py``). The visitor holds one
ticket with one short code; its view sums the characters up (waiting together for enough free
drones, being written, written) and lists each one: waiting, being written by drone k (named by
its board's place from the left, never by its internal id), written, or failed and written
again alone; a character written (done, or failed out of its bounds) carries the ink its drone
left, which the page draws on its board in place of the plan. No character's job id reaches the
page.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from bus.messages import JobState
from kiosk import wording
from kiosk.ink_view import written_view

FINAL = frozenset({"done", "failed", "cancelled", "rejected"})
PHRASE_INCOMPLETE = "phrase_incomplete"
"""Error code of a character ended, before its phrase began, because another of it could not be
written (docs/protocol.md): the page says the phrase goes whole or not at all."""
AWAITING = frozenset({"submitted", "awaiting_approval"})


def began(state: JobState) -> bool:
    """Whether a character's drone has begun writing it (or wrote it)."""
    return (
        state.state in ("writing", "done")
        or state.progress > 0
        or (state.state == "failed" and state.metrics is not None)
    )


def written_again(state: JobState, others: Sequence[JobState]) -> bool:
    """A character that failed after its phrase began, written again alone on its board (a
    phrase taken back before it began goes back whole: no character of it has begun)."""
    if state.state in FINAL or not any(began(o) for o in others):
        return False
    return state.attempts >= (1 if state.state == "queued" else 2)


def overall(states: Sequence[JobState]) -> str:
    """The phrase's state in one job-state name (for the page's queue place, ETA, bar)."""
    names = [s.state for s in states]
    if any(n in AWAITING for n in names):
        return "awaiting_approval"
    if all(n in FINAL for n in names):
        if all(n == "done" for n in names):
            return "done"
        if "rejected" in names:
            return "rejected"
        return "cancelled" if all(n == "cancelled" for n in names) else "failed"
    if any(began(s) for s in states):
        return "writing"
    return "assigned" if "assigned" in names else "queued"


def character_view(
    index: int,
    label: str,
    state: JobState | None,
    others: Sequence[JobState],
    places: Mapping[str, int],
) -> dict[str, Any]:
    """One character of the phrase, as the page lists it."""
    if state is None:
        return {
            "index": index,
            "label": label,
            "state": "checking",
            "final": False,
            "board": None,
            "progress": 0.0,
            "again": False,
            "failure": None,
            "with_phrase": False,
            "written": None,
        }
    on_board = state.state in ("assigned", "writing", "done", "failed")
    failure = state.error.code if state.error is not None and state.state == "failed" else None
    return {
        "index": index,
        "label": state.label or label,
        "state": state.state,
        "final": state.state in FINAL,
        "board": places.get(state.vehicle_id or "") if on_board else None,
        "progress": 1.0 if state.state == "done" else state.progress,
        "again": written_again(state, others),
        "failure": failure,
        "with_phrase": state.error is not None and state.error.code == PHRASE_INCOMPLETE,
        "written": written_view(state.metrics.written) if state.metrics is not None else None,
    }


def phrase_view(
    label: str,
    states: Sequence[JobState | None],
    places: Mapping[str, int] | None = None,
    *,
    show_paused: bool = False,
) -> dict[str, Any]:
    """The ticket of a phrase: the fields of a job's view (``kiosk.jobs.job_view``) summed up
    over its characters, and ``phrase``: its size, how many are written and each character.
    ``states``: the characters' newest states in reading order (None: not known yet; at least
    one is known)."""
    known = [s for s in states if s is not None]
    places = places or {}
    characters = [
        character_view(i, label[i : i + 1], s, [o for o in known if o is not s], places)
        for i, s in enumerate(states)
    ]
    state = overall(known)
    queued = [s for s in known if s.state == "queued"]
    positions = [s.queue_position for s in queued if s.queue_position is not None]
    etas = [s.eta_s for s in queued if s.eta_s is not None]
    said = next((s.error for s in known if s.error is not None and s.state == state), None)
    reason = wording.visitor_reason(said.reason) if said is not None else None
    written = sum(1 for s in known if s.state == "done")
    boards = sorted(c["board"] for c in characters if c["board"] is not None)
    eta_s = max(etas, default=None)
    position = min(positions, default=None)
    return {
        "job_id": known[0].job_id if states[0] is not None else None,
        "state": state,
        "final": len(known) == len(states) and all(s.state in FINAL for s in known),
        "label": label,
        "queue_position": position,
        "eta_s": eta_s,
        "vehicle_id": None,
        "place": None,
        "board": None,
        "attempts": max(s.attempts for s in known),
        "progress": sum(c["progress"] for c in characters) / len(characters),
        "metrics": None,
        "updated_at_s": max(s.updated_at_s for s in known),
        "show_paused": show_paused,
        "reason": reason,
        "failure": None,
        "phrase": {
            "size": len(states),
            "written": written,
            "boards": boards,
            "characters": characters,
        },
        "status_text": wording.phrase_status_text(
            state,
            size=len(states),
            written=written,
            boards=boards,
            eta_s=eta_s,
            queue_position=position,
            paused=show_paused,
            reason=reason,
        ),
    }

"""Every sentence the public reads, in one place: short, friendly, no jargon."""

from __future__ import annotations

import math
import unicodedata

TOO_LARGE = "That drawing is too big to send. Please clear it and draw something simpler."
TOO_MANY_STROKES = (
    "That drawing has too many strokes (at most {limit}). Please draw something simpler."
)
TOO_MANY_POINTS = "That drawing is too detailed. Please clear it and draw a little more simply."
BAD_JSON = "Something went wrong sending your character. Please reload the page and try again."
BAD_REQUEST = "Please either draw a character or type one, not both."
NOTHING = "Please draw a character or type one first."
SHORT_STROKE = "One of the strokes is just a dot. Please undo it and draw a line instead."
BAD_DRAWING = "We could not read this drawing. Please clear it and draw it again."
BAD_WIDTH = (
    "Some lines of this drawing are thinner or wider than the pen can write. Please clear it "
    "and draw it again."
)
TEXT_TOO_LONG = "Please type at most {limit} characters."
TEXT_ONE_CHAR = "Please type just one character."
TEXT_EMPTY = "Please type a character first."
NO_PHRASE = "This show writes one character at a time. Please type just one."
PHRASE_TOO_LONG = (
    "A phrase can have at most {limit} characters here: one for each board in the row."
)
PHRASE_TOO_SHORT = "A phrase has at least 2 characters. For one, type it on its own."
PHRASE_SPACES = "Each character of a phrase goes to its own board: please leave out the spaces."
NO_GLYPH = (
    "Sorry, the drones do not know how to write \u201c{char}\u201d yet. Please try another one."
)
BLOCKED = "Sorry, we cannot write that here. Please try something else."
RATE_LIMITED = (
    "You are sending characters very quickly! Please wait about {seconds} seconds and try again."
)
UNPLANNABLE = "The drones cannot fly this one. Please try a simpler character."
TOO_SMALL = (
    "That is just a tap. Please draw your character with lines, as big as you like it "
    "on the board: the drones keep its size and place."
)
TOO_LONG_FLIGHT = (
    "This one would take the drone about {seconds} seconds to write; the show allows "
    "{limit} seconds per character. Please draw it with fewer or shorter strokes."
)
NO_ORCHESTRATOR = "The drones' queue is not answering right now. Please try again in a minute."
QUEUE_FULL = "The queue is full right now. Please try again in a few minutes."
ORCHESTRATOR_REFUSED = "Sorry, this character could not be accepted. Please try another one."
SENDING = (
    "Your character is on its way: the drones' queue has not confirmed it yet. We keep trying, "
    "and it will be queued only once (this page updates by itself)."
)
CHECKING = "Your character is in the queue. Looking up where it is now..."
PENDING_FULL = (
    "The drones' queue is not answering right now, so your character was not sent. "
    "Please try again in a minute."
)
UNKNOWN_CODE = "We do not know this code. Please check it, or ask at the kiosk."
UNKNOWN_JOB = "We do not know this job. It may be from an earlier session."
NOT_YOUR_JOB = "You can only follow the characters you sent from this page."
REASON_CHARS_MAX = 200
"""Longest operator's reason a visitor is shown, in characters (a longer one is cut, with …)."""
_HIDDEN = frozenset(("Cc", "Cf", "Cs", "Zl", "Zp"))
"""Unicode categories of characters never shown: controls (``ESC``...), format characters
(bidirectional overrides), lone surrogates, line and paragraph separators."""
_JOINERS = frozenset("\u200c\u200d")
"""Zero-width (non-)joiners: format characters that emoji and several scripts need."""


def visitor_reason(text: str | None) -> str | None:
    """The operator's words as a visitor reads them: one line of plain text without control or
    format characters, at most :data:`REASON_CHARS_MAX` characters; None when nothing is left."""
    if not text:
        return None
    shown = "".join(
        " " if unicodedata.category(ch) in _HIDDEN and ch not in _JOINERS else ch for ch in text
    )
    line = " ".join(shown.split())
    if len(line) > REASON_CHARS_MAX:
        line = line[: REASON_CHARS_MAX - 1].rstrip() + "\u2026"
    return line or None


def duration_words(seconds: float | None) -> str:
    """A rough, friendly duration: "less than a minute", "about 3 minutes"."""
    if seconds is None or not math.isfinite(seconds):
        return "a little while"
    if seconds < 60.0:
        return "less than a minute"
    minutes = round(seconds / 60.0)
    return "about 1 minute" if minutes <= 1 else f"about {minutes} minutes"


def status_text(
    state: str,
    *,
    queue_position: int | None = None,
    eta_s: float | None = None,
    board: int | None = None,
    progress: float = 0.0,
    attempts: int = 0,
    place: str | None = None,
    paused: bool = False,
    reason: str | None = None,
    failure: str | None = None,
) -> str:
    """What the page says about a job in ``state`` (a bus JobStateName).

    ``board``: the position from the left of the writing vehicle's board, which names the drone
    for the public ("drone 2": an internal vehicle id is no name for a visitor); ``attempts``:
    assignments so far (a requeued job was assigned before); ``place``: where that board is
    ("board 2 from the left"); ``paused``: the show is paused (a
    queued job keeps its place, with no start time to promise); ``reason``: the operator's
    words on a rejection or cancellation (:func:`visitor_reason`); ``failure``: the code of a
    failed job's error (``writing_bounds``: written, out of the show's bounds)."""
    if state in ("submitted", "awaiting_approval"):
        return "Waiting for the show's operator to approve your character."
    if state == "queued":
        again = (
            "The drone had to land before finishing; your character is back in the queue. "
            if attempts >= 1
            else ""
        )
        if paused:
            kept = f", number {queue_position} in the queue" if queue_position else ""
            return (
                again + f"The show is paused for now. You keep your place{kept}: your character"
                " is written when the show goes on."
            )
        if queue_position is None:
            return again + "In the queue."
        line = "next in line" if queue_position <= 1 else f"number {queue_position} in the queue"
        return again + f"You are {line}. Your character should start in {duration_words(eta_s)}."
    drone = f"drone {board}" if board else "a drone"
    where = f" at {place}" if place else ""
    if state in ("assigned", "writing") and attempts >= 2:
        done = f" ({_percent(progress)} done)" if state == "writing" else ""
        return f"The first drone had to land; now {drone} is writing it{where}{done}."
    if state == "assigned":
        return f"Getting ready: {drone} is taking off to write your character{where}."
    if state == "writing":
        return f"Being written by {drone}{where}: {_percent(progress)} done."
    if state == "done":
        return f"Done! Your character was written by {drone}{where}."
    if state == "failed" and failure == "writing_bounds":
        return (
            f"Sorry, {drone} wrote your character{where}, but further from the plan than the show"
            " allows. This is the ink it left; the crew has been told."
        )
    if state == "failed":
        return "Sorry, something went wrong while writing your character. The crew has been told."
    said = f" The operator says: \u201c{reason}\u201d" if reason else ""
    if state == "cancelled":
        return "Your character was cancelled by the show's operator." + said
    if state == "rejected":
        return "Sorry, the show's operator did not approve this character." + said
    return "Please wait..."


def phrase_status_text(
    state: str,
    *,
    size: int,
    written: int,
    boards: list[int],
    eta_s: float | None = None,
    queue_position: int | None = None,
    paused: bool = False,
    reason: str | None = None,
) -> str:
    """What the page says about a phrase in ``state`` (:func:`kiosk.phrase_view.overall`):
    ``written`` of its ``size`` characters are written, by the drones of ``boards`` (their
    places from the left); a phrase waits for enough free drones side by side to write it
    together, never piecemeal."""
    if state in ("submitted", "awaiting_approval"):
        return "Waiting for the show's operator to approve your phrase."
    if state == "queued" and paused:
        return "The show is paused for now. Your phrase keeps its place in the queue."
    if state == "queued":
        ahead = f"number {queue_position} in the queue; " if queue_position else ""
        return (
            f"Your phrase waits for {size} free drones side by side, to write it together "
            f"({ahead}it should start in {duration_words(eta_s)})."
        )
    drones = ", ".join(str(b) for b in boards)
    if state in ("assigned", "writing"):
        return f"Drones {drones} are writing your phrase together: {written} of {size} written."
    if state == "done":
        return f"Done! Your phrase was written by drones {drones}, side by side."
    said = f" The operator says: \u201c{reason}\u201d" if reason else ""
    if state == "rejected":
        return "Sorry, the show's operator did not approve this phrase." + said
    if state == "cancelled":
        return "Your phrase was cancelled by the show's operator." + said
    return (
        f"Sorry, only {written} of the {size} characters could be written. The crew has been told."
    )


def _percent(fraction: float) -> str:
    return f"{round(100.0 * max(0.0, min(1.0, fraction)))}%"


def board_numbers(board_of_vehicle: dict[str, str], board_order: list[str]) -> dict[str, int]:
    """Vehicle id -> position of its board from the left, 1 first (the show file lists boards
    left to right)."""
    return {
        vehicle_id: board_order.index(board_id) + 1
        for vehicle_id, board_id in board_of_vehicle.items()
        if board_id in board_order
    }


def place_words(board_number: int | None) -> str | None:
    """Where a board is, in the visitors' words: "board 2 from the left"."""
    return None if board_number is None else f"board {board_number} from the left"

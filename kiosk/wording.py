"""Every sentence the public reads, in one place: short, friendly, no jargon."""

from __future__ import annotations

import math

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
) -> str:
    """What the page says about a job in ``state`` (a bus JobStateName).

    ``board``: the position from the left of the writing vehicle's board, which names the drone
    for the public ("drone 2": an internal vehicle id is no name for a visitor); ``attempts``:
    assignments so far (a requeued job was assigned before); ``place``: where that board is
    ("board 2 from the left"); ``paused``: the show is paused (a
    queued job keeps its place, with no start time to promise)."""
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
    if state == "failed":
        return "Sorry, something went wrong while writing your character. The crew has been told."
    if state == "cancelled":
        return "Your character was cancelled by the show's operator."
    if state == "rejected":
        return "Sorry, the show's operator did not approve this character."
    return "Please wait..."


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

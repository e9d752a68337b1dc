"""Jobs: their published state, their assignment to a vehicle, what their writing measured and
the ink it left."""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

import msgspec

from bus.messages.base import ErrorInfo, JobStateName, State

MAX_INK_PX = 256
"""Most pixels along either side of a :class:`WrittenInk` raster."""
MAX_INK_BYTES = MAX_INK_PX * MAX_INK_PX // 8
"""Most bytes of a :class:`WrittenInk` raster's packed bits (8 kB; base64 on the wire)."""
InkPixels = Annotated[int, msgspec.Meta(ge=1, le=MAX_INK_PX)]


class WrittenInk(State, frozen=True, kw_only=True):
    """The ink a vehicle left on its board for one job: a 1-bit raster for pictures, not scores.

    Pixel (row, column) covers board x from ``x_min + column * w`` and board y from
    ``y_max - (row + 1) * h`` (``w``, ``h``: extent over width/height in pixels): row 0 is the top
    (largest board y). ``bits`` holds the rows top first, each left to right, 8 pixels a byte,
    the first pixel in the most significant bit, no padding between rows (the last byte is
    padded with zeros); 1 is ink. On the wire ``bits`` is standard base64 (JSON string).
    """

    format: Literal["bitmap1"] = "bitmap1"
    """Layout of ``bits``; a new layout gets a new name."""
    width_px: InkPixels
    """Pixels per row (along board x)."""
    height_px: InkPixels
    """Rows (along board y)."""
    extent_m_board: tuple[float, float, float, float]
    """``(x_min, y_min, x_max, y_max)`` of the raster's outer pixel edges in the board frame
    (origin at the writing area's centre, x right, y up as the visitor sees the board), [m]."""
    bits: Annotated[bytes, msgspec.Meta(max_length=MAX_INK_BYTES)]
    """The packed pixels (see above): exactly ``ceil(width_px * height_px / 8)`` bytes."""

    def __post_init__(self) -> None:
        need = -(-self.width_px * self.height_px // 8)
        if len(self.bits) != need:
            raise ValueError(
                f"bits has {len(self.bits)} bytes; {self.width_px}x{self.height_px} pixels need "
                f"{need}"
            )
        x_min, y_min, x_max, y_max = self.extent_m_board
        if not all(math.isfinite(v) for v in self.extent_m_board) or not (
            x_max > x_min and y_max > y_min
        ):
            raise ValueError(f"extent_m_board {self.extent_m_board} is not a finite box")


class JobMetrics(State, frozen=True):
    """How well a character was written (see the simulator's metrics.json)."""

    rmse_pen_down_m: float | None
    """RMSE in [m] of the writing point while the pen was meant to be down; None: the pen never
    came down, so nothing was measured (null on the wire, v1 addition: was always a number)."""
    rmse_m: float
    max_error_m: float
    iou: float | None
    """Ink IoU of what was written against the whole target character (0: nothing of it
    written); None: the backend does not know its brush."""
    duration_s: float
    written: WrittenInk | None = None
    """The ink left on the board, when the vehicle knows its brush (sent with the ``done``
    report and on ``jobs/<id>``; the orchestrator keeps it out of ``fleet``)."""
    extra: dict[str, float] = {}
    """The kind's own figures, names with units: the wall hexarotor's ``rmse_ee_m``,
    ``rmse_base_m``, ``force_rmse_n``, ``width_rmse_m``; empty for kinds without any."""
    flown_fraction: float = 1.0
    """Fraction 0..1 of the plan's duration flown; below 1 the job was written in part (an abort):
    the errors cover what was flown, the IoU the whole target (v1 addition)."""


class PhrasePlace(State, frozen=True):
    """A job's place in a phrase written together (v1 addition)."""

    phrase_id: str
    """The phrase's id: its first character's job id."""
    index: int
    """Its character's place in reading order, 0 first (its board's place in the row too)."""
    size: int
    """Characters in the phrase."""


class JobState(State, frozen=True):
    """A job as the orchestrator knows it; published on every change."""

    job_id: str
    state: JobStateName
    label: str
    """The typed text, or ``drawing (N strokes)``."""
    kind: Literal["text", "strokes"]
    client_id: str
    created_at_s: float
    """Unix time of the submission."""
    updated_at_s: float
    priority: int = 0
    vehicle_id: str | None = None
    queue_position: int | None = None
    eta_s: float | None = None
    planned_duration_s: float | None = None
    progress: float = 0.0
    """Fraction of the planned trajectory flown, 0..1."""
    attempts: int = 0
    """How many times it was assigned (a lost vehicle's job is assigned again)."""
    metrics: JobMetrics | None = None
    error: ErrorInfo | None = None
    strokes: dict[str, Any] | None = None
    """The strokes document of a drawn job, for previews: only in ``jobs/<id>`` publications
    and ``snapshot`` replies while the job awaits approval or is queued (never in ``fleet``)."""
    phrase: PhrasePlace | None = None
    """Its place in a phrase written together; None: a job of its own (v1 addition)."""


class JobAssignment(State, frozen=True):
    """What a vehicle needs to write a job."""

    job_id: str
    text: str | None = None
    strokes: dict[str, Any] | None = None
    attempt: int = 1

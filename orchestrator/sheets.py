"""Sheets on the boards (pure): when a board waits for the crew's fresh sheet, or for its
surface to dry, and how long the crew takes.

Each board says (show file ``boards[].sheets``) what a written character costs it:

- ``per_character``: the character is the visitor's sheet, taken away (the Airshow): the board
  takes no job until the crew has put a fresh sheet on it and said so (``fresh_sheet``);
- ``when_spoiled``: characters are written over one another; only a half-written one needs a
  fresh sheet (``orchestrator/holders.py``, ``left_half_written``);
- ``none``: nothing is changed: a surface that clears itself (water on a cloth) takes no job for
  ``dry_s`` show seconds after a character.

The crew's turnaround (from a board's wait to its confirmation, show seconds) is the median of
its last :data:`TURNAROUNDS_KEPT` confirmations, ``policy.sheet_change_s`` until there is one;
the ETAs count it after every character of a ``per_character`` board.
"""

from __future__ import annotations

import statistics
from collections import deque
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Literal

SheetPolicy = Literal["per_character", "when_spoiled", "none"]
TURNAROUNDS_KEPT = 10
"""Confirmations the crew's turnaround is the median of: the day's pace, not the morning's."""


@dataclass(frozen=True)
class BoardSheets:
    """What a written character costs one board (``boards[].sheets`` and ``dry_s``)."""

    policy: SheetPolicy = "when_spoiled"
    dry_s: float = 0.0
    """Show seconds a ``none`` board takes no job after a character."""


class Sheets:
    """The boards of a show waiting for a sheet or drying, and the crew's pace."""

    def __init__(
        self,
        boards: Mapping[str, BoardSheets],
        *,
        time_scale: float,
        sheet_change_s: float,
        waiting: Iterable[str] = (),
        now_s: float = 0.0,
    ) -> None:
        """``waiting``: boards that waited for a sheet when the orchestrator last stopped (their
        wait counts from ``now_s``)."""
        self.boards = dict(boards)
        self.time_scale = time_scale
        self._default_turnaround_s = sheet_change_s
        self.waiting: dict[str, float] = {b: now_s for b in waiting if b in self.boards}
        """Board id -> Unix time [s] since which it waits for the crew's sheet."""
        self._dry_until_s: dict[str, float] = {}
        self._turnarounds_s: deque[float] = deque(maxlen=TURNAROUNDS_KEPT)

    def of(self, board_id: str) -> BoardSheets:
        return self.boards.get(board_id, BoardSheets())

    @property
    def turnaround_s(self) -> float:
        """The crew's expected turnaround, show seconds."""
        if not self._turnarounds_s:
            return self._default_turnaround_s
        return statistics.median(self._turnarounds_s)

    def written(self, board_id: str, now_s: float) -> bool:
        """A character was written in full on ``board_id``; True if the board now waits for the
        crew."""
        sheets = self.of(board_id)
        if sheets.policy == "per_character":
            self.waiting.setdefault(board_id, now_s)
            return True
        if sheets.policy == "none" and sheets.dry_s > 0.0:
            self._dry_until_s[board_id] = now_s + sheets.dry_s / self.time_scale
        return False

    def changed(self, board_id: str, now_s: float) -> bool:
        """The crew put a fresh sheet on ``board_id``; True if the board was waiting for one
        (its turnaround is counted)."""
        since_s = self.waiting.pop(board_id, None)
        if since_s is None:
            return False
        self._turnarounds_s.append((now_s - since_s) * self.time_scale)
        return True

    def busy(self, board_id: str, now_s: float) -> bool:
        """Whether ``board_id`` may take no job now (waiting for a sheet, or drying)."""
        return board_id in self.waiting or self._dry_until_s.get(board_id, 0.0) > now_s

    def free_at_s(self, board_id: str, now_s: float) -> float:
        """When ``board_id`` may take a job, Unix time [s], as far as sheets go (an estimate
        while the crew is on its way: never before now)."""
        since_s = self.waiting.get(board_id)
        due_s = now_s if since_s is None else since_s + self.turnaround_s / self.time_scale
        return max(now_s, due_s, self._dry_until_s.get(board_id, now_s))

    def after_character_s(self, board_id: str) -> float:
        """Show seconds a board takes no job after each character it is given (for ETAs)."""
        sheets = self.of(board_id)
        if sheets.policy == "per_character":
            return self.turnaround_s
        return sheets.dry_s if sheets.policy == "none" else 0.0

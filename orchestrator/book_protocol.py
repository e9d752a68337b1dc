"""What the decision modules read and do on the show's book: the type they share, below them.

The :class:`~orchestrator.core.Book` (``orchestrator/core.py``) holds the jobs and vehicles of a
show and composes the decisions: assignment, presence, reports, operator commands, requeue,
holders, phrases, battery swaps, clock offsets. Each of those takes the book as a
:class:`BookProtocol` (what it holds and the few primitives that keep it consistent), so the
decisions import this module and never ``core.py``: the import graph runs one way,
``core`` -> decisions -> ``book_protocol`` -> ``core_types`` (``pyproject.toml`` holds it there).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from typing import Protocol

from bus.messages import SubmitReply
from orchestrator.batteries import Swaps
from orchestrator.battery_drain import Drains
from orchestrator.core_types import CoreConfig, Effects, Level
from orchestrator.fleet import VehicleView
from orchestrator.jobs import Job
from orchestrator.kinds import KindMatch
from orchestrator.sheets import Sheets


class BookProtocol(Protocol):
    """All jobs and vehicles of a show as the decisions see them (``Book`` is the one)."""

    config: CoreConfig
    """The show's policy."""
    vehicles: dict[str, VehicleView]
    """Vehicle id -> what the orchestrator knows of it."""
    jobs: dict[str, Job]
    """Job id -> every job held in memory (unfinished ones and the latest finished)."""
    by_key: dict[tuple[str, str], str]
    """(client_id, idempotency_key) -> job id of every keyed submission in memory."""
    next_seq: int
    """Submission order of the next job."""
    queue_paused: bool
    """The operator paused the queue: nothing is assigned."""
    dirty_boards: set[str]
    """Boards left half-written: no job there until the operator's ``fresh_sheet``."""
    told_overdue: set[str]
    """Jobs whose overdue wait for their holder was alerted (``orchestrator/holders.py``)."""
    phrase_ready: dict[str, tuple[int, float]]
    """Job id -> (attempt, time [s]) of the latest unacknowledged *ready* report of a phrase's
    character (``orchestrator/phrases.py``)."""
    router_down_since_s: float | None
    """Since when the orchestrator has had no link to the router, [s] (None: it has one)."""
    kinds: KindMatch
    """Which kind may take a job and how long it would write it (``orchestrator/kinds.py``)."""
    sheets: Sheets
    """Boards waiting for the crew's sheet or drying (``orchestrator/sheets.py``)."""
    swaps: Swaps
    """Vehicles waiting for the crew's battery swap (``orchestrator/batteries.py``)."""
    drains: Drains
    """Each vehicle's drain learned from its reports (``orchestrator/battery_drain.py``)."""

    @property
    def job_counts(self) -> Counter[str]:
        """Jobs per state, every stored job counted."""
        ...

    def queue(self) -> list[Job]:
        """Queued jobs in the order they will be assigned."""
        ...

    def active_job_of(self, vehicle_id: str) -> Job | None:
        """The vehicle's assigned or writing job."""
        ...

    def awaited_by(self, vehicle_id: str) -> Job | None:
        """The queued job taken back from this lost vehicle that may wait for it."""
        ...

    def vehicles_with_jobs(self) -> set[str]:
        """Ids of the vehicles holding an active job."""
        ...

    def busy_boards(self) -> set[str]:
        """Boards of the active jobs."""
        ...

    def vehicle_ids(self, vehicle_id: str | None) -> Sequence[str]:
        """One vehicle (validated by the caller) or all."""
        ...

    def event(
        self,
        eff: Effects,
        now_s: float,
        level: Level,
        kind: str,
        message: str,
        *,
        vehicle_id: str | None = None,
        job_id: str | None = None,
    ) -> None:
        """Log an event into ``eff`` (and keep it as an open alert when its cause lasts)."""
        ...

    def put(self, eff: Effects, job: Job) -> Job:
        """Hold the new version of ``job`` and record it in ``eff`` (a phrase character that
        ends before its phrase began ends the phrase)."""
        ...

    def assign(self, eff: Effects, now_s: float) -> None:
        """Give queued jobs, in order, to ready vehicles whose board is free."""
        ...

    def settle(self, eff: Effects, now_s: float) -> Effects:
        """Add to ``eff.moved`` the queued jobs whose position or ETA the decision changed."""
        ...

    def submit_reply(self, job_id: str, now_s: float) -> SubmitReply:
        """The ``ok`` reply naming an accepted job, with its state, place and ETA."""
        ...

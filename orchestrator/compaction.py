"""Bounded history in the orchestrator's SQLite database: old finished jobs compacted, old events
deleted, freed pages given back to the file system.

What a finished job costs (Airshow soak, text jobs): its ink picture ``jobs.written`` ~4.4 kB
(about 5 kB of pages with its overflow chain), ``jobs.data`` ~0.9 kB, four events ~0.6 kB: about
6 kB a job, 9 MB per hour of show. Drawn jobs also carry their strokes (up to the 1 MB payload).

Three tiers, oldest first, while over budget (or past ``max_age_s``):

- compacted: a finished job's strokes document and ink picture are dropped; its record stays
  (id, sequence, state, idempotency key, text, label, client, vehicle, board, times, attempts,
  durations, metrics, error: ~1.2 kB with its index entries);
- folded (only over budget, once every older finished job is compacted): the record of the
  oldest compacted jobs is deleted, their number added to ``job_totals`` (per state) and their
  idempotency key kept in ``folded_keys`` with the job's id and state (~80 B);
- deleted: events (the log) older than the jobs just compacted (every event, once no job is
  left to compact).

Kept forever, so that counts per state stay exact and a repeated idempotency key still answers
with its job: the per-state totals and every key. Never touched: an unfinished job, any event
at or after the submission of the oldest unfinished job, and the newest ``keep_full_finished``
finished jobs (a ``snapshot`` reply shows the ink pictures of the newest); the newest
``keep_records`` finished jobs keep their record.

Work is done in small transactions (``batch_jobs`` jobs, ``batch_events`` events) and at most
``max_batches`` per call, so a call never holds the orchestrator's loop for long; the caller calls
again while :attr:`Compaction.more` says work is left.
"""

from __future__ import annotations

import math
import sqlite3
from collections import Counter
from dataclasses import dataclass

import msgspec

from orchestrator.finished import MAX_FINAL_JOBS
from orchestrator.jobs import FINAL_STATES, TRANSITIONS, Job

_FINAL = ",".join(f"'{state}'" for state in sorted(FINAL_STATES))
_UNFINISHED = ",".join(f"'{state}'" for state in sorted(set(TRANSITIONS) - FINAL_STATES))
FOLD_TABLES = """
CREATE TABLE IF NOT EXISTS job_totals (state TEXT PRIMARY KEY, count INTEGER NOT NULL);
CREATE TABLE IF NOT EXISTS folded_keys (
    idempotency_key TEXT PRIMARY KEY,
    job_id TEXT NOT NULL,
    state TEXT NOT NULL
) WITHOUT ROWID;
"""
"""Jobs folded per state; (scoped) idempotency key -> job id and state of folded jobs."""
FULL_FINISHED_INDEX = (
    "CREATE INDEX IF NOT EXISTS jobs_full_finished ON jobs (seq) "
    f"WHERE compacted = 0 AND state IN ({_FINAL})"
)
"""Finished jobs not yet compacted, by submission order (what compaction scans)."""

_job_decoder = msgspec.json.Decoder(Job)


@dataclass(frozen=True)
class HistoryPolicy:
    """How much history the database keeps (``storage.database_budget_mb``,
    ``storage.job_history_max_age_h`` in the show file)."""

    budget_bytes: int
    """Pages in use past which history is compacted, [bytes]."""
    max_age_s: float | None = None
    """Finished jobs and events older than this are compacted or deleted, [s]; None: no limit."""
    low_water: float = 0.8
    """Once over budget, compaction goes on down to this fraction of it."""
    keep_full_finished: int = 50
    """The newest finished jobs never compacted (at least 1)."""
    keep_records: int = MAX_FINAL_JOBS
    """The newest finished jobs never folded (at least 1): by default as many as the Book holds,
    so that a job it may still save is never folded (it would be counted twice)."""
    batch_jobs: int = 50
    """Jobs compacted per transaction (as many as finish between two scheduled calls)."""
    batch_events: int = 500
    """Events deleted per transaction."""
    max_batches: int = 1
    """Transactions per call (see ``benchmarks/bench_store.py`` for their time)."""

    @property
    def low_water_bytes(self) -> int:
        return int(self.budget_bytes * self.low_water)


@dataclass(frozen=True)
class Compaction:
    """What one call did."""

    jobs: int
    """Jobs compacted."""
    folded: int
    """Compacted jobs folded into the totals."""
    events: int
    """Events deleted."""
    before_bytes: int
    """Pages in use before, [bytes]."""
    after_bytes: int
    """Pages in use after, [bytes] (the file shrinks to this at the next WAL checkpoint)."""
    more: bool
    """Stopped at ``max_batches`` with work left: call again (with ``resume``)."""


@dataclass
class CompactionSchedule:
    """When the service compacts (in its loop's own time, between decisions): after every
    ``every_finished`` finished jobs, every ``period_s`` (the age limit moves with time), at
    start (an older database may be over budget), and at every chance while work is left."""

    every_finished: int = 50
    """Finished jobs between two calls."""
    period_s: float = 600.0
    """Longest time between two calls, [s]."""
    finished: int = 50
    """Jobs finished since the last call (due at start)."""
    next_s: float = 0.0
    """Time of the next periodic call, [s]."""
    more: bool = False
    """The last call left work: resume."""

    def due(self, now_s: float) -> bool:
        return self.more or self.finished >= self.every_finished or now_s >= self.next_s

    def ran(self, now_s: float, *, more: bool) -> None:
        """A call ended at ``now_s``; ``more``: it left work."""
        self.finished, self.next_s, self.more = 0, now_s + self.period_s, more


def compacted(job: Job) -> Job:
    """The record left of a compacted finished job: without its strokes document (its ink
    picture, in its own column, is dropped too)."""
    return msgspec.structs.replace(job, strokes=None)


def used_bytes(db: sqlite3.Connection) -> int:
    """Bytes of the database's pages in use (free pages excluded)."""
    pages = db.execute("PRAGMA page_count").fetchone()[0]
    free = db.execute("PRAGMA freelist_count").fetchone()[0]
    return int((pages - free) * db.execute("PRAGMA page_size").fetchone()[0])


def compact(
    db: sqlite3.Connection, policy: HistoryPolicy, now_s: float, *, resume: bool = False
) -> Compaction:
    """Compact old finished jobs, fold old records and delete old events while the database is
    over budget (from ``resume``: over its low water), and compact and delete what is older than
    ``max_age_s`` (records are folded only over budget); ``now_s``: Unix time.

    ``db`` is in autocommit mode (``isolation_level=None``); each batch is one transaction."""
    before = used_bytes(db)
    pressed = before > (policy.low_water_bytes if resume else policy.budget_bytes)
    jobs = folded = events = 0
    more = False
    if pressed or policy.max_age_s is not None:
        for batch in range(policy.max_batches):
            n_jobs, n_folded, n_events = _batch(db, policy, now_s, pressed)
            jobs, folded, events = jobs + n_jobs, folded + n_folded, events + n_events
            if not (n_jobs or n_folded or n_events):
                break
            pressed = pressed and used_bytes(db) > policy.low_water_bytes
            more = batch == policy.max_batches - 1
    return Compaction(jobs, folded, events, before, used_bytes(db), more)


def _batch(
    db: sqlite3.Connection, policy: HistoryPolicy, now_s: float, pressed: bool
) -> tuple[int, int, int]:
    """One transaction: the oldest compactable jobs (or, over budget with none left, the oldest
    compacted ones folded), then the events before them; the counts of each."""
    age_cutoff_s = -math.inf if policy.max_age_s is None else now_s - policy.max_age_s
    db.execute("BEGIN IMMEDIATE")
    try:
        kept_seq = _newest_finished_seq(db, policy.keep_full_finished)
        rows = _compactable(db, policy, kept_seq, age_cutoff_s, pressed)
        folded = 0
        if pressed and not rows:
            folded = _fold(db, _newest_finished_seq(db, policy.keep_records), policy.batch_jobs)
        db.executemany(
            "UPDATE jobs SET data = ?, written = NULL, compacted = 1 WHERE job_id = ?",
            [(msgspec.json.encode(compacted(job)), job.job_id) for job in rows],
        )
        event_cutoff_s = age_cutoff_s
        if pressed:  # the log up to the jobs just compacted; all of it when none are left
            newest_s = max((job.updated_at_s for job in rows), default=math.inf)
            event_cutoff_s = max(newest_s, age_cutoff_s)
        oldest = db.execute(
            "SELECT MIN(json_extract(data, '$.created_at_s')) FROM jobs "
            f"WHERE state IN ({_UNFINISHED})"
        ).fetchone()[0]
        if oldest is not None:
            event_cutoff_s = min(event_cutoff_s, oldest)
        deleted = 0
        if event_cutoff_s > -math.inf:
            deleted = db.execute(
                "DELETE FROM events WHERE id IN "
                "(SELECT id FROM events WHERE time_s < ? ORDER BY id LIMIT ?)",
                (event_cutoff_s, policy.batch_events),
            ).rowcount
        _give_back_free_pages(db)
    except BaseException:
        db.execute("ROLLBACK")
        raise
    db.execute("COMMIT")
    return len(rows), folded, deleted


def _newest_finished_seq(db: sqlite3.Connection, count: int) -> int:
    """The submission order of the oldest of the newest ``count`` finished jobs (0: fewer)."""
    row = db.execute(  # +state: walk the seq index from the end, not the state index
        f"SELECT seq FROM jobs WHERE +state IN ({_FINAL}) ORDER BY seq DESC LIMIT 1 OFFSET ?",
        (count - 1,),
    ).fetchone()
    return 0 if row is None else int(row[0])


def _compactable(
    db: sqlite3.Connection,
    policy: HistoryPolicy,
    kept_seq: int,
    age_cutoff_s: float,
    pressed: bool,
) -> list[Job]:
    """The oldest finished jobs not compacted yet, submitted before ``kept_seq`` (the oldest of
    the newest ``keep_full_finished``): any of them when ``pressed``, else those that finished
    before ``age_cutoff_s``."""
    age_term = "" if pressed else "AND json_extract(data, '$.updated_at_s') < :cutoff "
    rows = db.execute(
        "SELECT data FROM jobs INDEXED BY jobs_full_finished "
        f"WHERE compacted = 0 AND state IN ({_FINAL}) AND seq < :kept "
        f"{age_term}ORDER BY seq LIMIT :limit",
        {"kept": kept_seq, "cutoff": age_cutoff_s, "limit": policy.batch_jobs},
    )
    return [_job_decoder.decode(data) for (data,) in rows]


def _fold(db: sqlite3.Connection, kept_seq: int, limit: int) -> int:
    """Fold the oldest ``limit`` compacted jobs (submitted before ``kept_seq``) into the totals
    and the key table; their count."""
    rows = db.execute(  # the seq index from the start: compacted jobs are the oldest
        "SELECT job_id, state, idempotency_key FROM jobs WHERE +compacted = 1 AND seq < ? "
        "ORDER BY seq LIMIT ?",
        (kept_seq, limit),
    ).fetchall()
    db.executemany(
        "INSERT INTO folded_keys (idempotency_key, job_id, state) VALUES (?, ?, ?)",
        [(key, job_id, state) for job_id, state, key in rows if key is not None],
    )
    db.executemany(
        "INSERT INTO job_totals (state, count) VALUES (?, ?) "
        "ON CONFLICT(state) DO UPDATE SET count = count + excluded.count",
        Counter(state for _, state, _ in rows).items(),
    )
    db.executemany("DELETE FROM jobs WHERE job_id = ?", [(job_id,) for job_id, _, _ in rows])
    return len(rows)


def _give_back_free_pages(db: sqlite3.Connection) -> None:
    """Truncate the file by its free pages. ``incremental_vacuum`` frees one page per step of
    the statement and Python's sqlite3 steps a statement without result columns only once, so
    it is executed once per free page (microseconds each)."""
    for _ in range(db.execute("PRAGMA freelist_count").fetchone()[0]):
        db.execute("PRAGMA incremental_vacuum")

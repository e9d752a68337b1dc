"""Durable state of the orchestrator in SQLite: jobs, the event log, queue settings, open alerts.

Durability choice: WAL journal with ``synchronous=FULL``. In WAL mode ``NORMAL`` already survives
a crash of the process (kill -9): a committed transaction is in the WAL file. It does not survive
a power cut or an OS crash: the last commits may roll back because the WAL is not fsynced at each
commit. A submission acknowledged to a visitor must survive both, and submissions are rare (a few
per minute), so every commit is fsynced (FULL). Frequent, replaceable data (job progress,
telemetry) is never written here; only state changes are.

One transaction per decision (:meth:`JobStore.save`): the jobs it changed, its events and the
queue settings commit together, before the service replies or publishes. Every event is stored,
so the latest ones (:meth:`JobStore.events`, a ``snapshot`` reply's) outlive a restart; so do the
open alerts (``orchestrator/alerts.py``) and the batteries' swaps and drains
(``orchestrator/battery_records.py``), kept with the settings.
"""

from __future__ import annotations

import json
import sqlite3
from collections import Counter
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType

import msgspec

from bus.messages import Event, JobStateName, WrittenInk
from orchestrator.battery_records import BatteryRecords
from orchestrator.compaction import (
    FOLD_TABLES,
    FULL_FINISHED_INDEX,
    Compaction,
    HistoryPolicy,
    compact,
)
from orchestrator.disk_room import DiskReserve
from orchestrator.jobs import FINAL_STATES, Job

SCHEMA_VERSION = 4
"""1: jobs, events, settings. 2: ``jobs.idempotency_key`` (client id and key of a submission,
unique). 3: ``jobs.written`` (the ink picture of a done job, WrittenInk JSON). 4: ``jobs.compacted``
(1: a finished job's bulky parts dropped, ``orchestrator/compaction.py``), ``job_totals`` and
``folded_keys`` (what is left of the oldest finished jobs past the budget), and incremental
auto-vacuum (freed pages go back to the file system). All added in place to an older database
(version 4's auto-vacuum by one ``VACUUM``, which rewrites the file once)."""

_SCHEMA = """
CREATE TABLE IF NOT EXISTS jobs (
    job_id TEXT PRIMARY KEY,
    seq INTEGER NOT NULL UNIQUE,
    state TEXT NOT NULL,
    data BLOB NOT NULL
);
CREATE INDEX IF NOT EXISTS jobs_state ON jobs (state);
CREATE TABLE IF NOT EXISTS events (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    time_s REAL NOT NULL,
    data BLOB NOT NULL
);
CREATE TABLE IF NOT EXISTS settings (
    key TEXT PRIMARY KEY,
    value TEXT NOT NULL
);
"""

_KEY_INDEX = (
    "CREATE UNIQUE INDEX IF NOT EXISTS jobs_idempotency_key ON jobs (idempotency_key) "
    "WHERE idempotency_key IS NOT NULL"
)

_INCREMENTAL = 2
"""``PRAGMA auto_vacuum`` value of incremental mode."""

_job_decoder = msgspec.json.Decoder(Job)
_event_decoder = msgspec.json.Decoder(Event)
_events_decoder = msgspec.json.Decoder(list[Event])
_ink_decoder = msgspec.json.Decoder(WrittenInk)
_batteries_decoder = msgspec.json.Decoder(BatteryRecords)


class StoreError(RuntimeError):
    """The database cannot be opened or has an unknown schema."""


@dataclass(frozen=True)
class StoredState:
    """What a restarted orchestrator starts from."""

    jobs: list[Job]
    """Every unfinished job and the latest finished ones (:meth:`JobStore.load`), in submission
    order."""
    job_counts: dict[str, int]
    """Jobs per state, every stored job counted."""
    queue_paused: bool
    """The queue was paused."""
    paused_vehicles: list[str]
    """Vehicles the operator had paused, landed or stopped."""
    held_vehicles: list[str]
    """Vehicles held by the operator's land or estop (no job until ``release``)."""
    dirty_boards: list[str]
    """Boards left half-written (no job until ``fresh_sheet``)."""
    sheet_boards: list[str]
    """Boards waiting for the crew's sheet after a character (``orchestrator/sheets.py``)."""
    open_alerts: list[Event]
    """Alerts whose cause lasted when they were last stored, oldest first."""
    batteries: BatteryRecords
    """Battery swaps under way, the crew's pace, each vehicle's learned drain
    (``orchestrator/battery_records.py``)."""


@dataclass(frozen=True)
class KeyedJob:
    """What a repeated idempotency key is answered with (also of a folded job)."""

    job_id: str
    state: JobStateName


class JobStore:
    """The orchestrator's SQLite database; use as a context manager."""

    def __init__(self, path: str | Path, reserve: DiskReserve | None = None) -> None:
        """``reserve``: given up to write on when the disk is full (``orchestrator/disk_room``)."""
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.reserve = reserve
        self.reserve_given_up = False
        """A write found the disk full and the reserve was given up for it (the service says so
        and makes the reserve again once there is room)."""
        try:
            self._db = sqlite3.connect(self.path, isolation_level=None)
            self._db.execute("PRAGMA journal_mode=WAL")
            self._db.execute("PRAGMA synchronous=FULL")
            self._db.execute("PRAGMA busy_timeout=5000")
            version = self._db.execute("PRAGMA user_version").fetchone()[0]
            if version not in (0, 1, 2, 3, SCHEMA_VERSION):  # 0: new file; 1-3: migrated below
                raise StoreError(
                    f"{self.path}: schema version {version}, expected {SCHEMA_VERSION}"
                )
            self._db.execute("PRAGMA auto_vacuum=INCREMENTAL")  # takes effect on a new file
            self._db.executescript(_SCHEMA + FOLD_TABLES)
            self._migrate()
            if self._db.execute("PRAGMA auto_vacuum").fetchone()[0] != _INCREMENTAL:
                self._db.execute("VACUUM")  # an older file: rewritten once with the new mode
            self._db.execute(f"PRAGMA user_version={SCHEMA_VERSION}")
        except sqlite3.Error as exc:
            raise StoreError(f"{self.path}: {exc}") from exc

    def _migrate(self) -> None:
        """Bring an older (or new) jobs table to the current columns, in one transaction."""
        columns = {row[1] for row in self._db.execute("PRAGMA table_info(jobs)")}
        with _Transaction(self._db):
            if "idempotency_key" not in columns:
                self._db.execute("ALTER TABLE jobs ADD COLUMN idempotency_key TEXT")
            if "written" not in columns:
                self._db.execute("ALTER TABLE jobs ADD COLUMN written BLOB")
            if "compacted" not in columns:
                self._db.execute("ALTER TABLE jobs ADD COLUMN compacted INTEGER NOT NULL DEFAULT 0")
            self._db.execute(_KEY_INDEX)
            self._db.execute(FULL_FINISHED_INDEX)

    def __enter__(self) -> JobStore:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def close(self) -> None:
        self._db.close()

    def save(
        self,
        jobs: Iterable[Job] = (),
        events: Iterable[Event] = (),
        *,
        queue_paused: bool | None = None,
        paused_vehicles: Iterable[str] | None = None,
        held_vehicles: Iterable[str] | None = None,
        dirty_boards: Iterable[str] | None = None,
        sheet_boards: Iterable[str] | None = None,
        open_alerts: Iterable[Event] | None = None,
        written: Mapping[str, WrittenInk] | None = None,
        batteries: BatteryRecords | None = None,
    ) -> None:
        """Write changed jobs, new events, settings (``open_alerts`` replaces those stored) and
        ink pictures (job id -> picture of a job in ``jobs`` or stored before) in one durable
        transaction."""
        job_rows = [
            (j.job_id, j.seq, j.state, msgspec.json.encode(j), _scoped_key(j)) for j in jobs
        ]
        ink_rows = [(msgspec.json.encode(ink), job_id) for job_id, ink in (written or {}).items()]
        event_rows = [(e.time_s, msgspec.json.encode(e)) for e in events]
        settings: list[tuple[str, str]] = []
        if queue_paused is not None:
            settings.append(("queue_paused", json.dumps(queue_paused)))
        for key, names in (
            ("paused_vehicles", paused_vehicles),
            ("held_vehicles", held_vehicles),
            ("dirty_boards", dirty_boards),
            ("sheet_boards", sheet_boards),
        ):
            if names is not None:
                settings.append((key, json.dumps(sorted(names))))
        if open_alerts is not None:
            settings.append(("open_alerts", msgspec.json.encode(list(open_alerts)).decode()))
        if batteries is not None:
            settings.append(("batteries", msgspec.json.encode(batteries).decode()))
        if not (job_rows or event_rows or settings or ink_rows):
            return
        try:
            try:
                self._write(job_rows, event_rows, settings, ink_rows)
            except sqlite3.Error as exc:
                if not (_disk_full(exc) and self.reserve is not None and self.reserve.release()):
                    raise
                if self._db.in_transaction:  # a COMMIT that failed leaves it open
                    self._db.execute("ROLLBACK")
                self.reserve_given_up = True
                self._write(job_rows, event_rows, settings, ink_rows)
        except sqlite3.Error as exc:
            raise StoreError(f"{self.path}: {exc}") from exc

    def _write(
        self,
        job_rows: Sequence[tuple[str, int, str, bytes, str | None]],
        event_rows: Sequence[tuple[float, bytes]],
        settings: Sequence[tuple[str, str]],
        ink_rows: Sequence[tuple[bytes, str]] = (),
    ) -> None:
        with _Transaction(self._db):
            self._db.executemany(
                "INSERT INTO jobs (job_id, seq, state, data, idempotency_key) "
                "VALUES (?, ?, ?, ?, ?) "
                "ON CONFLICT(job_id) DO UPDATE SET state=excluded.state, data=excluded.data, "
                "compacted=0",
                job_rows,
            )
            self._db.executemany("INSERT INTO events (time_s, data) VALUES (?, ?)", event_rows)
            self._db.executemany(
                "INSERT INTO settings (key, value) VALUES (?, ?) "
                "ON CONFLICT(key) DO UPDATE SET value=excluded.value",
                settings,
            )
            self._db.executemany("UPDATE jobs SET written = ? WHERE job_id = ?", ink_rows)

    def load(self, max_final: int | None = None) -> StoredState:
        """The jobs (every unfinished one, and the latest ``max_final`` finished by submission
        order; None: all), jobs per state, and the settings."""
        final = ",".join(f"'{state}'" for state in sorted(FINAL_STATES))
        rows = self._db.execute(f"SELECT seq, data FROM jobs WHERE state NOT IN ({final})")
        kept = rows.fetchall()
        kept += self._db.execute(
            f"SELECT seq, data FROM jobs WHERE state IN ({final}) ORDER BY seq DESC LIMIT ?",
            (-1 if max_final is None else max_final,),
        ).fetchall()
        jobs = [_job_decoder.decode(data) for _, data in sorted(kept)]
        counts: Counter[str] = Counter(
            dict(self._db.execute("SELECT state, COUNT(*) FROM jobs GROUP BY state"))
        )
        counts.update(dict(self._db.execute("SELECT state, count FROM job_totals")))
        settings = dict(self._db.execute("SELECT key, value FROM settings").fetchall())
        return StoredState(
            jobs=jobs,
            job_counts=dict(counts),
            queue_paused=bool(json.loads(settings.get("queue_paused", "false"))),
            paused_vehicles=list(json.loads(settings.get("paused_vehicles", "[]"))),
            held_vehicles=list(json.loads(settings.get("held_vehicles", "[]"))),
            dirty_boards=list(json.loads(settings.get("dirty_boards", "[]"))),
            sheet_boards=list(json.loads(settings.get("sheet_boards", "[]"))),
            open_alerts=_events_decoder.decode(settings.get("open_alerts", "[]")),
            batteries=_batteries_decoder.decode(settings.get("batteries", "{}")),
        )

    def job(self, job_id: str) -> Job | None:
        """One job as stored."""
        row = self._db.execute("SELECT data FROM jobs WHERE job_id = ?", (job_id,)).fetchone()
        return _job_decoder.decode(row[0]) if row else None

    def job_by_key(self, client_id: str, idempotency_key: str) -> KeyedJob | None:
        """The job submitted by ``client_id`` with ``idempotency_key`` (folded ones too)."""
        key = _scope(client_id, idempotency_key)
        row = self._db.execute(
            "SELECT job_id, state FROM jobs WHERE idempotency_key = ? UNION ALL "
            "SELECT job_id, state FROM folded_keys WHERE idempotency_key = ?",
            (key, key),
        ).fetchone()
        return KeyedJob(job_id=row[0], state=row[1]) if row else None

    def written(self, job_ids: Iterable[str]) -> dict[str, WrittenInk]:
        """The stored ink pictures of ``job_ids`` (jobs without one are left out)."""
        ids = list(dict.fromkeys(job_ids))
        found: dict[str, WrittenInk] = {}
        for start in range(0, len(ids), 500):  # SQLite's bound parameters per statement
            chunk = ids[start : start + 500]
            marks = ",".join("?" * len(chunk))
            rows = self._db.execute(
                "SELECT job_id, written FROM jobs "
                f"WHERE written IS NOT NULL AND job_id IN ({marks})",
                chunk,
            )
            found.update((job_id, _ink_decoder.decode(data)) for job_id, data in rows)
        return found

    def compact(self, policy: HistoryPolicy, now_s: float, *, resume: bool = False) -> Compaction:
        """Bound the history by ``policy`` (orchestrator/compaction.py); ``now_s``: Unix time."""
        try:
            return compact(self._db, policy, now_s, resume=resume)
        except sqlite3.Error as exc:
            raise StoreError(f"{self.path}: {exc}") from exc

    def events(self, limit: int = 200) -> list[Event]:
        """The latest events, oldest first."""
        rows = self._db.execute(
            "SELECT data FROM events ORDER BY id DESC LIMIT ?", (limit,)
        ).fetchall()
        return [_event_decoder.decode(r[0]) for r in reversed(rows)]


def _scoped_key(job: Job) -> str | None:
    """The unique column value: a key is unique per client (``client_id``, unit separator, key)."""
    if job.idempotency_key is None:
        return None
    return _scope(job.client_id, job.idempotency_key)


def _scope(client_id: str, idempotency_key: str) -> str:
    return f"{client_id}\x1f{idempotency_key}"


def _disk_full(exc: sqlite3.Error) -> bool:
    """Whether SQLite found the disk full (``SQLITE_FULL``; an I/O error on writing, extended
    codes included, is what a full disk gives in WAL mode as often)."""
    primary = getattr(exc, "sqlite_errorcode", 0) & 0xFF
    return primary in (sqlite3.SQLITE_FULL, sqlite3.SQLITE_IOERR)


class _Transaction:
    def __init__(self, db: sqlite3.Connection) -> None:
        self._db = db

    def __enter__(self) -> None:
        self._db.execute("BEGIN IMMEDIATE")

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self._db.execute("ROLLBACK" if exc_type else "COMMIT")

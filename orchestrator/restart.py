"""What a Book takes up from the store when the orchestrator starts (pure).

The service loads what the store kept of the show (``orchestrator/store.py``) and hands it to
the :class:`~orchestrator.core.Book`, which builds its state from it here: the declared vehicles
with the operator's pauses and holds, the jobs, the boards that waited for a fresh sheet or the
crew's sheet, the vehicles' learned drains. What the show no longer declares is left out.
"""

from __future__ import annotations

from collections.abc import Container, Iterable, Iterator

from orchestrator.battery_drain import Drains
from orchestrator.battery_records import BatteryRecords
from orchestrator.core_types import CoreConfig
from orchestrator.fleet import VehicleView
from orchestrator.jobs import Job, update
from orchestrator.sheets import Sheets


def vehicles_at_start(
    config: CoreConfig, now_s: float, *, paused: Iterable[str], held: Iterable[str]
) -> dict[str, VehicleView]:
    """Vehicle id -> view of each declared vehicle: none heard yet (gone since ``now_s``), the
    ``paused`` and ``held`` ones so again."""
    views = {v.vehicle_id: VehicleView(v, gone_since_s=now_s) for v in config.vehicles}
    for vid in paused:
        if vid in views:
            views[vid].paused = True
    for vid in held:
        if vid in views:
            views[vid].paused = views[vid].held = True
    return views


def jobs_at_start(jobs: Iterable[Job], now_s: float) -> Iterator[Job]:
    """The stored jobs; active jobs must be confirmed by their vehicle again (their assignment
    counts from ``now_s``)."""
    for job in jobs:
        yield update(job, now_s, assigned_at_s=now_s) if job.active else job


def keys_of(jobs: Iterable[Job]) -> dict[tuple[str, str], str]:
    """(client_id, idempotency_key) -> job id of every keyed submission among ``jobs``."""
    return {
        (j.client_id, j.idempotency_key): j.job_id for j in jobs if j.idempotency_key is not None
    }


def dirty_boards_at_start(config: CoreConfig, dirty: Iterable[str]) -> set[str]:
    """The boards left half-written, of those the declared vehicles write on."""
    boards = {v.board_id for v in config.vehicles}
    return {b for b in dirty if b in boards}


def sheets_at_start(config: CoreConfig, waiting: Iterable[str], now_s: float) -> Sheets:
    """The show's boards, those ``waiting`` for the crew's sheet waiting again from ``now_s``."""
    return Sheets(
        dict(config.boards),
        time_scale=config.eta.time_scale,
        sheet_change_s=config.sheet_change_s,
        waiting=waiting,
        now_s=now_s,
    )


def drains_at_start(stored: BatteryRecords, vehicles: Container[str]) -> Drains:
    """The drains learned of the declared ``vehicles`` (ids)."""
    return Drains(r for r in stored.drains if r.vehicle_id in vehicles)

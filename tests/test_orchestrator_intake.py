"""Vehicle statuses at scale (issue 15): merged per vehicle, decided in chunks, never ahead of a
job's acknowledgement; a heartbeat that changes nothing sweeps nothing."""

from __future__ import annotations

import asyncio
import logging
from pathlib import Path
from typing import Any

import pytest
import zenoh

from bus.codec import encode
from bus.keys import ShowKeys
from bus.messages import AgentReport, VehicleStatus
from bus.pubsub import subscribe
from orchestrator.core import Book
from orchestrator.jobs import Job, transition
from orchestrator.outputs import core_config
from orchestrator.service import STATUS_CHUNK, OrchestratorService
from orchestrator.store import JobStore
from showfile import Show, load_show

ROOT = Path(__file__).resolve().parents[1]
VEHICLES = 3 * STATUS_CHUNK


def _wide_show(count: int) -> Show:
    """The Airshow show with ``count`` vehicles, each over its own board."""
    base = load_show(ROOT / "shows" / "airshow-2014.yaml")
    boards = [base.boards[0].model_copy(update={"id": f"b{k}"}) for k in range(count)]
    vehicles = [
        base.vehicles[0].model_copy(update={"id": f"uav{k}", "board": f"b{k}"})
        for k in range(count)
    ]
    return base.model_copy(update={"boards": tuple(boards), "vehicles": tuple(vehicles)})


class _Session:
    """Takes what the service publishes, in order."""

    def __init__(self) -> None:
        self.published: list[str] = []

    def put(self, key: str, payload: bytes, **_: Any) -> None:
        self.published.append(key)


def _writing_job(show: Show) -> Job:
    vehicle = show.vehicles[0]
    job = Job(
        job_id="j1", seq=1, state="queued", kind="text", text="A", label="A",
        client_id="test", created_at_s=1.0, updated_at_s=1.0,
    )  # fmt: skip
    job = transition(job, "assigned", 1.0, vehicle_id=vehicle.id, board_id=vehicle.board)
    return transition(job, "writing", 1.0)


def _status(vehicle_id: str, job_id: str | None = None, message: str = "") -> VehicleStatus:
    return VehicleStatus(
        vehicle_id=vehicle_id,
        kind="quadrotor-brush",
        state="idle" if job_id is None else "writing",
        job_id=job_id,
        message=message,
    )


def test_a_status_flood_does_not_delay_an_acknowledgement(tmp_path: Path) -> None:
    show = _wide_show(VEHICLES)
    keys = ShowKeys(show.show_id)
    decided: list[str] = []

    async def scenario(service: OrchestratorService) -> int:
        intake = service.open_status_intake()
        for vehicle in show.vehicles:
            job_id = "j1" if vehicle.id == "uav0" else None
            service.receive_status(keys.vehicle_status(vehicle.id), _status(vehicle.id, job_id))
        book_status = service.book.status

        def counting(status: VehicleStatus, now_s: float) -> Any:
            decided.append(status.vehicle_id)
            return book_status(status, now_s)

        service.book.status = counting  # type: ignore[method-assign]
        # as from Zenoh's threads: the flood is scheduled first, then the report
        deciding = asyncio.create_task(service.decide_statuses(intake.take_nowait().values()))
        report = AgentReport(vehicle_id="uav0", job_id="j1", event="progress", progress=0.5)

        async def acknowledge() -> int:
            reply = await service.on_report("uav0", report)
            assert reply.ok, reply
            return len(decided)  # statuses decided before the reply left

        answered_after = await asyncio.create_task(acknowledge())
        await deciding
        return answered_after

    with JobStore(tmp_path / "s.sqlite3") as store:
        store.save([_writing_job(show)])
        service = OrchestratorService(show, _Session(), store)  # type: ignore[arg-type]
        answered_after = asyncio.run(scenario(service))
    assert answered_after == STATUS_CHUNK  # one chunk, not the whole flood, came first
    assert len(decided) == VEHICLES


def test_statuses_are_merged_per_vehicle_and_kept_only_on_their_own_key(tmp_path: Path) -> None:
    show = _wide_show(3)
    keys = ShowKeys(show.show_id)

    async def scenario(service: OrchestratorService) -> dict[str, VehicleStatus]:
        intake = service.open_status_intake()
        service.receive_status(keys.vehicle_status("uav0"), _status("uav0", message="older"))
        service.receive_status(keys.vehicle_status("uav0"), _status("uav0", message="newer"))
        service.receive_status(keys.vehicle_status("uav1"), _status("uav2"))  # uav1 poses
        return intake.take_nowait()

    with JobStore(tmp_path / "s.sqlite3") as store:
        service = OrchestratorService(show, _Session(), store)  # type: ignore[arg-type]
        held = asyncio.run(scenario(service))
    assert list(held) == ["uav0"] and held["uav0"].message == "newer"


def test_a_heartbeat_decides_about_its_own_vehicle_only() -> None:
    show = _wide_show(2)
    book = Book(core_config(show), now_s=0.0)
    for vid in ("uav0", "uav1"):
        book.liveliness(vid, True, 0.0)
        book.status(_status(vid), 0.0)
    lost_after_s = show.policy.lost_after_s
    for k in range(1, int(lost_after_s / 0.1) - 1):  # the timer, while both are quiet
        assert not book.tick(0.1 * k).events
    late_s = lost_after_s + 0.1  # uav1 has been silent too long by then
    eff = book.status(_status("uav0"), late_s)
    assert not eff.events and not eff.fleet_changed and not book.vehicles["uav1"].lost
    eff = book.tick(late_s)  # the timer finds it
    assert book.vehicles["uav1"].lost and [e.kind for e in eff.events] == ["vehicle_lost"]


class _Sample:
    """What a Zenoh subscriber callback is given (the parts ``bus.pubsub`` reads)."""

    def __init__(self, key: str, payload: bytes) -> None:
        self.key_expr, self.kind, self._payload = key, zenoh.SampleKind.PUT, payload

    @property
    def payload(self) -> _Sample:
        return self

    def to_bytes(self) -> bytes:
        return self._payload


def test_a_malformed_status_is_refused_with_one_line_and_never_decided(
    caplog: pytest.LogCaptureFixture,
) -> None:
    keys = ShowKeys("show")
    received: list[VehicleStatus] = []
    callbacks: list[Any] = []

    class _Declaring:
        def declare_subscriber(self, key_expr: str, callback: Any) -> None:
            callbacks.append(callback)

    service_side = lambda key, status: received.append(status)  # noqa: E731
    subscribe(_Declaring(), keys.vehicle_status_all, VehicleStatus, service_side)  # type: ignore[arg-type]
    payload = encode(_status("uav0")).replace(b'"idle"', b'"dancing"')
    with caplog.at_level(logging.WARNING, logger="bus.pubsub"):
        callbacks[0](_Sample(keys.vehicle_status("uav0"), payload))
    assert not received
    [line] = [r.getMessage() for r in caplog.records]
    assert line.startswith("undecodable VehicleStatus on skyquill/show/vehicles/uav0/status: ")
    assert "dancing" in line and "\n" not in line


def test_fleet_changes_are_merged_into_the_timers_next_snapshot(tmp_path: Path) -> None:
    show = _wide_show(3)
    keys = ShowKeys(show.show_id)
    session = _Session()
    with JobStore(tmp_path / "s.sqlite3") as store:
        service = OrchestratorService(show, session, store)  # type: ignore[arg-type]
        for k, vehicle in enumerate(show.vehicles):  # three vehicles come: three changes
            service.apply(service.book.liveliness(vehicle.id, True, 1.0 + k))
    assert keys.fleet not in session.published and service.fleet_changed

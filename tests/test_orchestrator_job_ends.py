"""An ``ended`` report (what a vehicle wrote of a job stopped by a cancel, a land, an emergency
stop, a fault or its lease; issue 34) decides nothing: the orchestrator's job, its vehicles and
boards come out exactly as without it, whether it arrives before or after the orchestrator
learns of the end, and it sends no command to anyone. A cancelled job keeps its metrics.

Each case is run twice on real Books (pure): the show of two vehicles, uav1 writing j1, then the
end as the orchestrator sees it today (the operator's command, or the vehicle's statuses); one
twin also gets uav1's ``ended`` report. uav2 is idle, so a job that goes back to the queue is
given to it at once (the ended report then comes from a vehicle that no longer holds the job).
"""

from __future__ import annotations

from collections.abc import Callable

import msgspec
import pytest

from bus.messages import (
    AgentReport,
    ErrorInfo,
    JobMetrics,
    OperatorCommand,
    SubmitRequest,
    VehicleStatus,
)
from orchestrator.core import Book, CoreConfig
from orchestrator.fleet import VehicleInfo
from orchestrator.jobs import Job

VEHICLES = (
    VehicleInfo("uav1", "quadrotor-brush", "b1"),
    VehicleInfo("uav2", "quadrotor-brush", "b2"),
)
END_S = 10.0
"""Show time in [s] of the end."""
METRICS = JobMetrics(
    rmse_pen_down_m=0.004,
    rmse_m=0.006,
    max_error_m=0.02,
    iou=0.31,
    duration_s=6.0,
    flown_fraction=0.42,
)


def _status(book: Book, vid: str, state: str, job_id: str | None, now_s: float) -> None:
    book.status(
        VehicleStatus(vehicle_id=vid, kind="quadrotor-brush", state=state, job_id=job_id),  # type: ignore[arg-type]
        now_s,
    )


def _writing() -> Book:
    """uav1 writes j1 (started, acknowledged); uav2 idle."""
    book = Book(CoreConfig(show_id="t", vehicles=VEHICLES), now_s=0.0)
    book.liveliness("uav1", True, 0.0)
    _status(book, "uav1", "idle", None, 0.0)
    reply, _ = book.submit("j1", SubmitRequest(text="十"), label="十", estimate_s=20.0, now_s=1.0)
    assert reply.ok and (book.jobs["j1"].state, book.jobs["j1"].vehicle_id) == ("assigned", "uav1")
    started = AgentReport(vehicle_id="uav1", job_id="j1", event="started", planned_duration_s=9)
    assert book.report(started, 2.0)[0].ok
    book.liveliness("uav2", True, 2.0)
    for t_s in (2.0, 5.0, 8.0, END_S - 0.5):
        _status(book, "uav1", "writing", "j1", t_s)
        _status(book, "uav2", "idle", None, t_s)
    assert (book.jobs["j1"].state, book.jobs["j1"].progress) == ("writing", 0.0)
    return book


def _operator(command: str, **kw: object) -> Callable[[Book], None]:
    def end(book: Book) -> None:
        reply, _ = book.operator(OperatorCommand(command=command, **kw), END_S)  # type: ignore[arg-type]
        assert reply.ok, reply

    return end


def _says(state: str) -> Callable[[Book], None]:
    """uav1's statuses from the end on: ``state`` without the job (a fault; a job given up on
    its lease), heard with uav2's until the orchestrator's confirmation grace has passed."""

    def end(book: Book) -> None:
        t_s = END_S
        while t_s <= END_S + book.config.confirm_grace_s + 0.5:
            _status(book, "uav1", state, None, t_s)
            given = book.active_job_of("uav2")  # j1, once handed back: uav2 flies it
            if given is None:
                _status(book, "uav2", "idle", None, t_s)
            else:
                _status(book, "uav2", "taking_off", given.job_id, t_s)
            book.tick(t_s)
            t_s += 0.5

    return end


def _stopped(command: str, state: str) -> Callable[[Book], None]:
    """The operator's ``command`` to uav1, then uav1's statuses in ``state`` without the job: its
    word that it did not write it in full (till then the job waits for it,
    ``orchestrator/holders.py``: its writing may have ended just before the command)."""
    order, word = _operator(command, vehicle_id="uav1"), _says(state)

    def end(book: Book) -> None:
        order(book)
        word(book)

    return end


ENDS: dict[str, tuple[Callable[[Book], None], str, tuple[str, str | None]]] = {
    "cancel": (_operator("cancel", job_id="j1"), "cancelled", ("cancelled", "uav1")),
    "land": (_stopped("land", "landing"), "landed_by_operator", ("assigned", "uav2")),
    "estop": (_stopped("estop", "fault"), "estop", ("assigned", "uav2")),
    "fault": (_says("fault"), "vehicle_fault", ("assigned", "uav2")),
    "lease": (_says("returning"), "given_up", ("assigned", "uav2")),
}
"""Each end: how the orchestrator learns it, the agent's reason, and the job's state and vehicle
that follow today."""


def _ended(reason: str) -> AgentReport:
    info = ErrorInfo(code=reason, message=f"{reason} at 42% of its plan")
    return AgentReport(
        vehicle_id="uav1", job_id="j1", event="ended", progress=0.42, metrics=METRICS, error=info
    )


def _same_but_metrics(job: Job, twin: Job) -> None:
    a = msgspec.structs.replace(job, metrics=None, updated_at_s=0.0)
    b = msgspec.structs.replace(twin, metrics=None, updated_at_s=0.0)
    assert a == b


def _same_fleet(book: Book, twin: Book) -> None:
    assert book.dirty_boards == twin.dirty_boards
    assert book.queue_paused == twin.queue_paused
    for vid in ("uav1", "uav2"):
        view, other = book.vehicles[vid], twin.vehicles[vid]
        assert (view.held, view.paused, view.refused_until_s, view.mismatch_since_s) == (
            other.held, other.paused, other.refused_until_s, other.mismatch_since_s
        )  # fmt: skip


@pytest.mark.parametrize("when", ["after", "before"])
@pytest.mark.parametrize("kind", sorted(ENDS))
def test_an_ended_report_changes_nothing_of_the_job(kind: str, when: str) -> None:
    end, reason, (state, vehicle) = ENDS[kind]
    today, told = _writing(), _writing()
    end(today)
    if when == "before":  # the vehicle's report overtook the orchestrator's own news
        reply, eff = told.report(_ended(reason), END_S - 0.1)
        end(told)
    else:
        end(told)
        reply, eff = told.report(_ended(reason), END_S + 5.0)
    assert reply.ok and eff.commands == []
    job, twin = told.jobs["j1"], today.jobs["j1"]
    assert (twin.state, twin.vehicle_id) == (state, vehicle)  # what happens today
    assert (job.state, job.vehicle_id, job.attempts, job.progress) == (
        twin.state, twin.vehicle_id, twin.attempts, twin.progress
    )  # fmt: skip
    _same_but_metrics(job, twin)
    _same_fleet(told, today)
    if kind == "cancel" and when == "after":  # the cancelled job keeps what was written
        assert job.metrics == METRICS and eff.jobs["j1"].metrics == METRICS
    else:
        assert job.metrics == twin.metrics
    (line,) = [e for e in eff.events if e.kind == "job_ended"]
    assert line.message == f"十: uav1 stopped it ({reason}) at 42% of its plan, IoU 0.31"


def test_a_vehicle_that_wrote_nothing_is_said_to_have_written_nothing() -> None:
    book = _writing()
    _operator("land", vehicle_id="uav1")(book)
    info = ErrorInfo(code="landed_by_operator", message="landed")
    nothing = AgentReport(vehicle_id="uav1", job_id="j1", event="ended", error=info)
    reply, eff = book.report(nothing, END_S + 1.0)
    assert reply.ok and eff.commands == [] and "j1" not in eff.jobs
    (line,) = [e for e in eff.events if e.kind == "job_ended"]
    assert line.message.endswith("(landed_by_operator) before its writing began: nothing written")

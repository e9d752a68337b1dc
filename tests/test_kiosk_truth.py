"""What the kiosk tells visitors is true: from the orchestrator's pure Book to the page's view.

The operator's reason for a rejection or cancellation reaches the visitor as one bounded line of
plain text, never the operator's name or a default sentence; a character written out of the
show's bounds keeps the ink it left; a drawing too long to fly is refused with how long it
would take against the show's limit, even when another kind could not plan it at all.
"""

from __future__ import annotations

import unicodedata
from dataclasses import dataclass
from typing import Any

import msgspec
import pytest
from hypothesis import given
from hypothesis import strategies as st

from bus.messages import (
    AgentReport,
    ErrorInfo,
    JobMetrics,
    OperatorCommand,
    ShowSnapshot,
    SubmitRequest,
    VehicleStatus,
    WrittenInk,
)
from kiosk import wording
from kiosk.errors import RejectedError
from kiosk.jobs import job_view
from kiosk.limits import Submission
from kiosk.preview import plan_preview
from kiosk.settings import KioskSettings
from orchestrator.core import Book, CoreConfig, Effects
from orchestrator.fleet import VehicleInfo
from orchestrator.jobs import to_state
from orchestrator.written import attach_written, with_written
from planner.errors import PlannerError

INK = WrittenInk(width_px=8, height_px=2, extent_m_board=(-0.6, -0.15, 0.6, 0.15), bits=b"\x81\x18")
OFF = JobMetrics(rmse_pen_down_m=0.09, rmse_m=0.1, max_error_m=0.2, iou=0.2, duration_s=9.0)
"""A character written far from its plan: out of the show's bounds."""


def _book() -> Book:
    config = CoreConfig(
        show_id="t", vehicles=(VehicleInfo("uav1", "quadrotor-brush", "b1"),), moderation=True
    )
    book = Book(config, now_s=0.0)
    book.liveliness("uav1", True, 0.0)
    book.status(VehicleStatus(vehicle_id="uav1", kind="quadrotor-brush", state="idle"), 0.0)
    for job_id in ("j1", "j2"):
        book.submit(job_id, SubmitRequest(text="永"), label="永", estimate_s=5.0, now_s=1.0)
    return book


def _seen(book: Book, job_id: str, eff: Effects | None = None) -> dict[str, Any]:
    """The page's view of ``job_id`` as the orchestrator publishes it on ``jobs/<id>``."""
    state = to_state(book.jobs[job_id])
    if eff is not None:
        state = with_written(state, eff.written.get(job_id))
    return job_view(state, {"uav1": 1})


def test_the_operators_reason_reaches_the_visitor_and_nothing_else_of_the_operator() -> None:
    book = _book()
    reason = "Too close to a logo,\n sorry \x1b[31m\u202eplease try another"
    book.operator(OperatorCommand(command="reject", job_id="j1", reason=reason), 2.0)
    view = _seen(book, "j1")
    assert view["reason"] == "Too close to a logo, sorry [31m please try another"
    assert view["status_text"].endswith(f"The operator says: \u201c{view['reason']}\u201d")
    book.operator(OperatorCommand(command="cancel", job_id="j2", operator="alice"), 2.0)
    view = _seen(book, "j2")
    assert book.jobs["j2"].error.message == "cancelled by alice"  # for the console, not the page
    assert view["reason"] is None and "alice" not in str(view)
    assert view["status_text"] == "Your character was cancelled by the show's operator."


def test_a_bulk_rejection_carries_its_reason_to_every_visitor() -> None:
    book = _book()
    command = OperatorCommand(command="reject", job_ids=["j1", "j2"], reason="x" * 1000)
    assert book.operator(command, 2.0)[0].ok
    for job_id in ("j1", "j2"):
        shown = _seen(book, job_id)["reason"]
        assert len(shown) == wording.REASON_CHARS_MAX and shown.endswith("x\u2026")


@given(st.text(max_size=1200))
def test_a_reason_is_one_bounded_line_of_plain_text(text: str) -> None:
    shown = wording.visitor_reason(text)
    if shown is None:
        return
    assert 0 < len(shown) <= wording.REASON_CHARS_MAX and shown == shown.strip()
    hidden = [ch for ch in shown if unicodedata.category(ch) in ("Cc", "Cs", "Zl", "Zp")]
    assert hidden == [] and "\u202e" not in shown and "\x1b" not in shown


def test_a_character_written_out_of_its_bounds_keeps_the_ink_it_left() -> None:
    book = _book()
    book.operator(OperatorCommand(command="approve", job_id="j1"), 2.0)
    book.report(AgentReport(vehicle_id="uav1", job_id="j1", event="started"), 3.0)
    error = ErrorInfo(code="writing_bounds", message="written out of bounds: IoU 0.20 < 0.30")
    report = AgentReport(
        vehicle_id="uav1", job_id="j1", event="failed", progress=1.0,
        metrics=msgspec.structs.replace(OFF, written=INK), error=error,
    )  # fmt: skip
    reply, eff = book.report(report, 12.0)
    assert reply.ok and book.jobs["j1"].state == "failed"
    assert book.jobs["j1"].metrics == OFF  # kept, its picture apart (stored with the job)
    view = _seen(book, "j1", eff)
    assert view["failure"] == "writing_bounds" and view["metrics"]["written"]["bits"] == "gRg="
    assert "further from the plan" in view["status_text"] and "drone 1" in view["status_text"]
    # a page opened later asks the snapshot: the picture comes with the failed job too
    snapshot = ShowSnapshot(
        show_id="t", time_s=13.0, queue_paused=False, jobs=[to_state(book.jobs["j1"])], vehicles=[]
    )
    (late,) = attach_written(snapshot, lambda ids: dict.fromkeys(ids, INK), 10_000).jobs
    assert late.metrics is not None and late.metrics.written == INK
    unwritten = job_view(
        msgspec.structs.replace(late, error=ErrorInfo(code="geofence", message=""))
    )
    assert unwritten["failure"] == "geofence" and "went wrong" in unwritten["status_text"]


@dataclass(frozen=True)
class _Kind:
    name: str


@dataclass(frozen=True)
class _Plan:
    duration_s: float


@dataclass(frozen=True)
class _Job:
    plan: _Plan


@dataclass(frozen=True)
class _Setup:
    """A kind's planning as the preview calls it: refuses, or plans ``duration_s`` of writing."""

    kind: _Kind
    duration_s: float | None

    def plan(self, glyph: object) -> _Job:
        if self.duration_s is None:
            raise PlannerError("no trajectory within the limits")
        return _Job(_Plan(self.duration_s))


@pytest.mark.parametrize("cannot_first", [True, False])
def test_a_drawing_too_long_to_fly_is_told_how_long_it_would_take(cannot_first: bool) -> None:
    kinds = [_Setup(_Kind("wall"), None), _Setup(_Kind("brush"), 137.4)]
    if not cannot_first:
        kinds.reverse()
    stubs: tuple[Any, ...] = tuple(kinds)
    kiosk = KioskSettings(show_id="t", preview_kinds=stubs, max_flight_s=90.0)
    with pytest.raises(RejectedError) as refused:
        plan_preview(Submission(text="永", strokes=None), kiosk)
    error = refused.value.to_json_dict()
    assert error["code"] == "too_long" and error["flight_s"] == 137.4  # never "cannot fly"
    message = str(error["message"])
    assert "about 137 seconds" in message and "allows 90 seconds" in message

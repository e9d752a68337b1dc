"""What the agent's report outbox logs (``vehicle_agent/reports.py``): a *ready* report held for
its phrase is routine (every ready period per waiting vehicle): one debug line, no warning; a
report refused for another reason stays a warning."""

from __future__ import annotations

import asyncio
import logging
from typing import Any

import pytest

from bus.keys import ShowKeys
from bus.messages import AgentReport, CommandReply, ErrorInfo
from bus.rpc import NoReplyError, RemoteError
from vehicle_agent import reports
from vehicle_agent.lease import JobLease
from vehicle_agent.reports import ReportOutbox


def _deliver(monkeypatch: pytest.MonkeyPatch, reply: CommandReply) -> ReportOutbox:
    async def answer(*_args: Any, **_kw: Any) -> CommandReply:
        return reply

    monkeypatch.setattr(reports, "aquery_one", answer)
    outbox = ReportOutbox(
        ShowKeys("t"), "uav2", JobLease(lost_after_s=1.5), retry_s=0.1, timeout_s=1.0,
        running_job=lambda: "p1", refused=lambda _why: None, settled=lambda _job: None,
    )  # fmt: skip
    ready = AgentReport(vehicle_id="uav2", job_id="p1", event="holding", planned_duration_s=8.0)
    assert asyncio.run(outbox._deliver(None, ready))  # type: ignore[arg-type]
    return outbox


def _refusal(code: str, message: str) -> CommandReply:
    return CommandReply(ok=False, message=message, error=ErrorInfo(code=code, message=message))


def test_a_ready_report_held_for_its_phrase_is_one_debug_line(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    waits = _refusal("phrase_waits", "年 waits for 快 乐 to start together")
    with caplog.at_level(logging.DEBUG, logger="vehicle_agent.reports"):
        _deliver(monkeypatch, waits)
    [record] = caplog.records
    assert record.levelno == logging.DEBUG
    assert (
        record.getMessage() == "uav2: p1 holds for its phrase: 年 waits for 快 乐 to start together"
    )


def test_a_report_refused_otherwise_is_still_a_warning(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    with caplog.at_level(logging.DEBUG, logger="vehicle_agent.reports"):
        _deliver(monkeypatch, _refusal("bad_state", "p1 is done"))
    assert [(r.levelno, r.getMessage()) for r in caplog.records] == [
        (logging.WARNING, "uav2: report holding not accepted: p1 is done")
    ]


@pytest.mark.parametrize(
    ("silence", "resent"),
    [
        (NoReplyError("no reply on t/report (only: Timeout)"), True),
        (RemoteError(ErrorInfo(code="busy", message="busy")), True),
        (RemoteError(ErrorInfo(code="not_assigned", message="not yours")), False),
    ],
)
def test_a_done_report_is_settled_only_by_the_orchestrators_own_answer(
    monkeypatch: pytest.MonkeyPatch, silence: Exception, resent: bool
) -> None:
    """No answer (``bus.rpc`` also reports Zenoh's own "Timeout" as none) or an orchestrator
    that could not take it is no receipt: the result is sent again, not let go (the job would be
    written twice); a refusal is the orchestrator's answer."""

    async def error_reply(*_args: Any, **_kw: Any) -> CommandReply:
        raise silence

    monkeypatch.setattr(reports, "aquery_one", error_reply)
    outbox = ReportOutbox(
        ShowKeys("t"), "uav1", JobLease(lost_after_s=1.5), retry_s=0.1, timeout_s=1.0,
        running_job=lambda: None, refused=lambda _why: None, settled=lambda _job: None,
    )  # fmt: skip
    done = AgentReport(vehicle_id="uav1", job_id="j1", event="done")
    delivered = asyncio.run(outbox._deliver(None, done))  # type: ignore[arg-type]
    assert delivered is not resent  # delivered: answered, and a result then settled

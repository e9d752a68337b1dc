"""Bulk moderation in the console (Pilot, demo show, no bus): mark waiting jobs one by one or a
whole client's, then reject them all after one question."""

from __future__ import annotations

from typing import Any

import pytest
from test_tui_operator_keys import play, settle

from bus.messages import JobState, OperatorCommand
from tui.app import ConsoleApp
from tui.demo import DEMO_TIME_S
from tui.widgets.confirm_screen import ConfirmScreen

pytestmark = pytest.mark.timeout(60)

FLOOD = "flood\x1b[2J[blink]"
"""A client id as hostile as the bus lets through to a console's model."""


def _flood_job(job_id: str, state: str, seconds_ago: float, **extra: Any) -> JobState:
    return JobState(
        job_id=job_id,
        state=state,  # type: ignore[arg-type]
        label="x",
        kind="text",
        client_id=FLOOD,
        created_at_s=DEMO_TIME_S - seconds_ago,
        updated_at_s=DEMO_TIME_S - seconds_ago,
        **extra,
    )


def _sends(app: ConsoleApp) -> list[OperatorCommand]:
    """Record what the console sends instead of sending it."""
    sent: list[OperatorCommand] = []
    app.send = sent.append  # type: ignore[method-assign, assignment]
    return sent


def test_a_clients_waiting_jobs_are_marked_at_once_and_rejected_after_one_question() -> None:
    async def scenario(app: ConsoleApp, pilot: Any) -> None:
        sent = _sends(app)
        for i in range(5):
            app.model.apply(_flood_job(f"f-{i}", "awaiting_approval", 20 - i), DEMO_TIME_S)
        app.model.apply(_flood_job("f-q", "queued", 25, queue_position=3), DEMO_TIME_S)
        await settle(pilot)
        await pilot.press("tab", "R")  # nothing marked: refused, nothing asked
        await settle(pilot)
        assert not isinstance(app.screen, ConfirmScreen) and sent == []
        assert app._queue.selected_job == "j-0006"
        await pilot.press("space")
        await settle(pilot)
        assert [j.job_id for j in app._queue.marked_jobs()] == ["j-0006"]
        assert app._queue.border_subtitle == "1 marked · R: reject"
        await pilot.press("space", "down", "down", "M")  # unmark j-0006; all of f-0's client
        await settle(pilot)
        assert app._queue.selected_job == "f-0"
        marked = [j.job_id for j in app._queue.marked_jobs()]
        assert sorted(marked) == ["f-0", "f-1", "f-2", "f-3", "f-4", "f-q"]
        await pilot.press("R")
        await settle(pilot)
        assert isinstance(app.screen, ConfirmScreen)
        question = app.screen.question
        assert "6 marked job(s) from flood␛[2J[blink]?" in question  # data, not codes
        assert "5 awaiting approval are rejected and 1 queued are cancelled" in question
        await pilot.press(*"junk", "enter")
        await settle(pilot)
        flood = ["f-0", "f-1", "f-2", "f-3", "f-4"]
        assert sent == [
            OperatorCommand(command="reject", job_ids=flood, reason="junk"),
            OperatorCommand(command="cancel", job_ids=["f-q"], reason="junk"),
        ]
        for job_id in flood:  # the orchestrator's answer arrives: the marks go with the jobs
            app.model.apply(_flood_job(job_id, "rejected", 0), DEMO_TIME_S)
        await pilot.pause(0.3)
        assert [j.job_id for j in app._queue.marked_jobs()] == ["f-q"]

    play(scenario)


def test_only_waiting_jobs_can_be_marked() -> None:
    async def scenario(app: ConsoleApp, pilot: Any) -> None:
        sent = _sends(app)
        await pilot.press("tab", *["down"] * 6, "space")
        await settle(pilot)
        assert app.model.job(app._queue.selected_job).state == "failed"  # type: ignore[union-attr]
        assert app._queue.marked_jobs() == [] and app._queue.border_subtitle == ""
        await pilot.press("R")
        await settle(pilot)
        assert not isinstance(app.screen, ConfirmScreen) and sent == []

    play(scenario)

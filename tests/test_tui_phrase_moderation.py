"""The console moderates a phrase as one submission: ``a`` or ``r`` on any of its characters
asks first, and its question says the whole phrase is approved or rejected (the orchestrator
does so, ``orchestrator/operator.py``); a lone job is approved at once as before."""

from __future__ import annotations

from typing import Any

import msgspec
import pytest
from test_tui_model import job
from test_tui_operator_keys import play, sent, settle

from bus.messages import JobState, OperatorCommand, PhrasePlace
from tui import commands as cmd
from tui.app import ConsoleApp
from tui.widgets.confirm_screen import ConfirmScreen

pytestmark = pytest.mark.timeout(60)


def _phrase(text: str = "新年快乐") -> list[JobState]:
    return [
        msgspec.structs.replace(
            job(f"p{i}", "awaiting_approval", 1.0 + i, priority=10),
            label=char,
            phrase=PhrasePlace(phrase_id="p0", index=i, size=len(text)),
        )
        for i, char in enumerate(text)
    ]


def test_a_phrase_character_asks_and_names_the_whole_phrase() -> None:
    phrase = _phrase()
    approve = cmd.job_request("approve", phrase[2], phrase)
    assert isinstance(approve, cmd.Ask) and approve.label == "Approve phrase"
    assert "the phrase 新年快乐 (4 characters, p0)" in approve.question
    assert "all 4 characters are approved" in approve.question
    assert approve.commands == (OperatorCommand(command="approve", job_id="p2"),)
    reject = cmd.job_request("reject", phrase[1], phrase)
    assert isinstance(reject, cmd.Ask) and reject.reason_prompt is not None
    assert "the reason goes to every one" in reject.question
    assert reject.commands == (OperatorCommand(command="reject", job_id="p1"),)
    # a lone job is approved at once, with no question
    lone = job("j1", "awaiting_approval")
    assert cmd.job_request("approve", lone, []) == OperatorCommand(command="approve", job_id="j1")


def test_the_console_confirms_a_phrase_approval_before_sending_it() -> None:
    async def scenario(app: ConsoleApp, pilot: Any) -> None:
        for state in _phrase():
            app.model.apply(state, 0.0)
        await pilot.press("tab", "home")
        await settle(pilot)
        for _ in range(12):  # to a character of the phrase
            if (app._queue.selected_job or "").startswith("p"):
                break
            await pilot.press("down")
            await settle(pilot)
        selected = app._queue.selected_job
        assert selected is not None and selected.startswith("p"), selected
        assert [j.label for j in app.model.phrase_of(app.model.job(selected))] == list("新年快乐")
        await pilot.press("a")
        await settle(pilot)
        assert isinstance(app.screen, ConfirmScreen) and sent(app) is None
        assert "Approve the phrase 新年快乐 (4 characters, p0)?" in app.screen.question
        await pilot.press("y")
        await settle(pilot)
        assert sent(app) == OperatorCommand(command="approve", job_id=selected)

    play(scenario)

"""The console's cancel question says what happens to the job and to its visitor, as the reject
question does: the queue, a vehicle on its way, a character being written, a phrase that has not
begun (cancelled whole, ``orchestrator/phrases.py``) and one that has; and the reason goes to
the visitor."""

from __future__ import annotations

import msgspec
import pytest
from test_tui_model import job

from bus.messages import JobState, OperatorCommand, PhrasePlace
from tui import commands as cmd

TOLD = "The visitor's ticket says the operator cancelled it, with your reason if you give one."


def _ask(job_state: JobState, phrase: list[JobState] | None = None) -> cmd.Ask:
    ask = cmd.job_request("cancel", job_state, phrase or [])
    assert isinstance(ask, cmd.Ask)
    assert ask.commands == (OperatorCommand(command="cancel", job_id=job_state.job_id),)
    assert ask.reason_prompt == "reason (optional, shown to the visitor)"
    return ask


@pytest.mark.parametrize(
    ("state", "progress", "outcome"),
    [
        ("queued", 0.0, "It leaves the queue and will not be written."),
        ("assigned", 0.0, "Its vehicle returns and lands before writing it."),
        (
            "writing",
            0.4,
            "The vehicle writing it lifts its pen, returns and lands; what it wrote stays on the"
            " board, unfinished, and is not written again.",
        ),
    ],
)
def test_the_cancel_question_says_what_happens_to_the_job_and_the_visitor(
    state: str, progress: float, outcome: str
) -> None:
    ask = _ask(job("j1", state, progress=progress))
    assert ask.question == f"Cancel j1 (J1)?\n{outcome}\n{TOLD}"


def test_a_character_of_a_phrase_not_begun_says_the_whole_phrase_goes() -> None:
    phrase = [
        msgspec.structs.replace(
            job(f"p{i}", "assigned"), label=c, phrase=PhrasePlace(phrase_id="p0", index=i, size=2)
        )
        for i, c in enumerate("新年")
    ]
    ask = _ask(phrase[1], phrase)
    assert "Its phrase has not begun: all 2 characters are cancelled" in ask.question
    begun = [msgspec.structs.replace(phrase[0], state="writing", progress=0.3), phrase[1]]
    ask = _ask(begun[1], begun)
    assert "Its vehicle returns and lands before writing it." in ask.question
    assert "The other characters of its phrase go on." in ask.question

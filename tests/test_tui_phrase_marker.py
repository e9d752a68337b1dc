"""The queue marks a phrase's characters as one group (``tui/widgets/queue_table``)."""

from __future__ import annotations

import msgspec
from test_tui_model import job

from bus.messages import PhrasePlace
from tui.rows import QueueRow
from tui.widgets.queue_table import row_cells


def test_a_phrases_characters_carry_their_place_in_it_and_a_lone_job_none() -> None:
    place = PhrasePlace(phrase_id="p0", index=1, size=4)
    phrased = msgspec.structs.replace(job("p1", "queued"), label="年", phrase=place)
    assert row_cells(QueueRow("queued", phrased))[1].plain == "年 ⁞2/4"
    alone = msgspec.structs.replace(job("j1", "queued"), label="永")
    assert row_cells(QueueRow("queued", alone))[1].plain == "永"

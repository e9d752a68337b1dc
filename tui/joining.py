"""A late joiner's catch-up: ask the orchestrator for the whole show until it answers.

The console asks once when it starts, again when the orchestrator (re)appears, and again when a
job's final message was lost (:attr:`tui.model.ConsoleModel.ended_unheard`). A loaded
orchestrator may leave an ask unanswered: it is asked again every :data:`SNAPSHOT_RETRY_S`, and
the event log says so once until the snapshot comes.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable

from tui.link import ConsoleLink
from tui.model import ConsoleModel

SNAPSHOT_RETRY_S = 2.0
"""Between asks for the show's snapshot while the orchestrator does not answer, [s] (each ask
waits up to 2 s: a loaded orchestrator answers in well under that)."""


class ShowJoiner:
    """Asks for the show's snapshot and applies it to the model; one ask at a time."""

    def __init__(self, link: ConsoleLink, model: ConsoleModel, clock: Callable[[], float]) -> None:
        self.link = link
        self.model = model
        self.clock = clock
        """Console time in [s]."""
        self.asking = False
        """A snapshot is being asked for: a lost end waits for this ask, not another."""
        self._wait_said = False

    async def join(self) -> None:
        """Ask until answered, then apply the whole snapshot (``full``: what it leaves out
        has ended)."""
        self.asking = True
        try:
            while (snapshot := await self.link.query_snapshot()) is None:
                if not self._wait_said:
                    message = (
                        "no snapshot from the orchestrator yet:"
                        f" asking every {SNAPSHOT_RETRY_S:.0f} s"
                    )
                    self.model.events.note(self.clock(), "warning", "console", message)
                    self._wait_said = True
                await asyncio.sleep(SNAPSHOT_RETRY_S)
            self._wait_said = False
            self.model.apply_snapshot(snapshot, self.clock(), full=True)
        finally:
            self.asking = False

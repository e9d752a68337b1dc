"""Server-sent events of one ticket: its view now, then every change, until it is final.

Between changes a ``live`` frame every ``beat_s`` says whether the information is current
(``{"stale": true}`` when the orchestrator's 1 Hz fleet snapshot stopped arriving), so the page
can say "the show is slow to answer" within seconds, and notice a silent stream itself (its
connection to the kiosk lost).
"""

from __future__ import annotations

import asyncio
import json
from collections.abc import AsyncIterator, Mapping
from typing import Any

from bus.bridge import ChannelClosedError
from kiosk.link import OrchestratorLink

BEAT_S = 0.5
"""Period of the ``live`` frames, [s] (the page calls the stream lost after 2.5 s of silence)."""


def sse_event(event: str, data: dict[str, Any]) -> str:
    """One SSE frame (``event:`` and a single-line JSON ``data:``)."""
    return (
        f"event: {event}\ndata: {json.dumps(data, ensure_ascii=False, separators=(',', ':'))}\n\n"
    )


async def job_events(
    link: OrchestratorLink,
    ticket: str,
    *,
    stale_after_s: float,
    places: Mapping[str, int] | None = None,
    beat_s: float = BEAT_S,
) -> AsyncIterator[str]:
    """Frames for one ticket's page; ends after the first final view."""
    with link.watch(ticket) as channel:
        job = link.book.get(ticket)
        if job is None:
            return
        if link.book.unknown(job):
            await link.fetch(job.job_id or "")
        last: dict[str, Any] | None = None
        while True:
            view = link.book.view(job, places)
            if view != last:
                last = view
                yield sse_event("job", view)
                if view["final"]:
                    return
            yield sse_event("live", {"stale": link.stale(stale_after_s)})
            try:
                await asyncio.wait_for(channel.get(), timeout=beat_s)
            except TimeoutError:
                continue
            except ChannelClosedError:  # the server is stopping; the page reconnects later
                return

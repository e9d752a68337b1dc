"""Server-sent events of one job: its state now, then every change, until it is final."""

from __future__ import annotations

import asyncio
import json
from collections.abc import AsyncIterator
from typing import Any

from bus.bridge import ChannelClosedError
from bus.messages import JobState
from kiosk.jobs import FINAL_STATES, job_view
from kiosk.link import OrchestratorLink

KEEPALIVE_S = 15.0
"""Comment line sent when nothing happened for this long, so proxies keep the stream open."""


def sse_event(event: str, data: dict[str, Any]) -> str:
    """One SSE frame (``event:`` and a single-line JSON ``data:``)."""
    return (
        f"event: {event}\ndata: {json.dumps(data, ensure_ascii=False, separators=(',', ':'))}\n\n"
    )


async def job_events(
    link: OrchestratorLink, job_id: str, *, keepalive_s: float = KEEPALIVE_S
) -> AsyncIterator[str]:
    """Frames for one job's page; ends after the first final state."""
    with link.watch(job_id) as channel:
        state = link.book.state(job_id)
        if state is None:
            state = await link.fetch(job_id)
        last: JobState | None = None
        if state is not None:
            yield sse_event("job", job_view(state))
            last = state
            if state.state in FINAL_STATES:
                return
        while True:
            try:
                state = await asyncio.wait_for(channel.get(), timeout=keepalive_s)
            except TimeoutError:
                yield ": keepalive\n\n"
                continue
            except ChannelClosedError:  # the server is stopping; the page reconnects later
                return
            if state == last:
                continue
            last = state
            yield sse_event("job", job_view(state))
            if state.state in FINAL_STATES:
                return

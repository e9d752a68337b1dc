"""Planned writing durations for queue ETAs: a text's rough estimate replaced by the planner's
(one worker thread, bounded work and memory), kept per text for its next submission."""

from __future__ import annotations

import asyncio
import logging
from concurrent.futures import ThreadPoolExecutor
from typing import Any

from orchestrator.submissions import planned_durations_s
from showfile import Show

log = logging.getLogger(__name__)

MAX_PENDING_PLANS = 64
"""Planner runs for ETAs waiting at most (one worker, about 25-100 ms each); beyond, submissions
keep their rough estimate. 64 gives every submission of a burst its planned duration (the ETA
figures of ``bench_show.py --eta`` need it; 4 left most of a 16-character burst on rough
estimates); the planning caches it fills are bounded (``CACHED_DURATIONS``, the glyph and
planner LRU caches), so the orchestrator's memory stays within the bus fuzz's bound."""
CACHED_DURATIONS = 256
"""Texts whose planned durations are kept for their next submission (a show's corpus repeats;
the kiosk's visitors do not)."""


class DurationEstimates:
    """Planned durations per vehicle kind, [s] of show time, by text."""

    def __init__(self, show: Show) -> None:
        self.show = show
        self.cached: dict[str, dict[str, float]] = {}
        """Text key -> planned durations by kind, oldest first."""
        self._planner = ThreadPoolExecutor(max_workers=1, thread_name_prefix="eta-planner")
        self._pending = 0

    def remember(self, cache_key: str, durations: dict[str, float]) -> None:
        """Keep a text's planned durations for its next submission; the oldest text is
        forgotten past ``CACHED_DURATIONS`` (visitors type without end)."""
        self.cached[cache_key] = durations
        if len(self.cached) > CACHED_DURATIONS:
            del self.cached[next(iter(self.cached))]

    async def planned(self, job_id: str, glyph: Any, cache_key: str | None) -> dict[str, float]:
        """The glyph's planned durations (empty: none, keep the rough estimate; best effort)."""
        durations = self.cached.get(cache_key) if cache_key else None
        if durations is not None:
            return durations
        if self._pending >= MAX_PENDING_PLANS:
            return {}  # a burst of submissions: keep the rough estimates
        self._pending += 1
        loop = asyncio.get_running_loop()
        try:
            durations = await loop.run_in_executor(
                self._planner, planned_durations_s, glyph, self.show
            )
        except Exception:
            log.exception("planning %s for its ETA failed", job_id)
            return {}
        finally:
            self._pending -= 1
        if durations and cache_key:
            self.remember(cache_key, durations)
        return durations or {}

    def shutdown(self) -> None:
        """Stop the worker, dropping plans not started."""
        self._planner.shutdown(wait=False, cancel_futures=True)

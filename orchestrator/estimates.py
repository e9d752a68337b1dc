"""Planned writing durations for queue ETAs: a text's rough estimate replaced by the planner's
(one worker thread, bounded work and memory), kept per text for its next submission."""

from __future__ import annotations

import asyncio
import logging
from concurrent.futures import ThreadPoolExecutor
from typing import Any

from orchestrator.kinds import KindPlans
from orchestrator.submissions import planned_durations_s
from showfile import Show

log = logging.getLogger(__name__)

MAX_PENDING_PLANS = 64
"""Planner runs for ETAs waiting at most (one worker, about 25-100 ms each); beyond, submissions
keep their rough estimate. 64 gives every submission of a burst its planned duration (the ETA
figures of ``bench_show.py --eta`` need it; 4 left most of a 16-character burst on rough
estimates); the planning caches it fills are bounded (``CACHED_DURATIONS``, the glyph and
planner LRU caches), so the orchestrator's memory stays within the bus fuzz's bound."""
NOT_PLANNED = KindPlans({})
"""What a job not planned for its ETA keeps: its rough estimate, every kind allowed."""
CACHED_DURATIONS = 256
"""Texts whose planned durations are kept for their next submission (a show's corpus repeats;
the kiosk's visitors do not)."""


class DurationEstimates:
    """Planned durations per vehicle kind, [s] of show time, and the kinds that cannot plan it,
    by text."""

    def __init__(self, show: Show) -> None:
        self.show = show
        self.cached: dict[str, KindPlans] = {}
        """Text key -> its plans by kind, oldest first."""
        self._planner = ThreadPoolExecutor(max_workers=1, thread_name_prefix="eta-planner")
        self._pending = 0

    def remember(self, cache_key: str, plans: KindPlans) -> None:
        """Keep a text's plans for its next submission; the oldest text is forgotten past
        ``CACHED_DURATIONS`` (visitors type without end)."""
        self.cached[cache_key] = plans
        if len(self.cached) > CACHED_DURATIONS:
            del self.cached[next(iter(self.cached))]

    async def planned(self, job_id: str, glyph: Any, cache_key: str | None) -> KindPlans:
        """The glyph's plans by kind (none: keep the rough estimate; best effort)."""
        plans = self.cached.get(cache_key) if cache_key else None
        if plans is not None:
            return plans
        if self._pending >= MAX_PENDING_PLANS:
            return NOT_PLANNED  # a burst of submissions: keep the rough estimates
        self._pending += 1
        loop = asyncio.get_running_loop()
        try:
            plans = await loop.run_in_executor(self._planner, planned_durations_s, glyph, self.show)
        except Exception:
            log.exception("planning %s for its ETA failed", job_id)
            return NOT_PLANNED
        finally:
            self._pending -= 1
        if cache_key and plans.known:
            self.remember(cache_key, plans)
        return plans

    def shutdown(self) -> None:
        """Stop the worker, dropping plans not started."""
        self._planner.shutdown(wait=False, cancel_futures=True)

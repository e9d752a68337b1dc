"""The kiosk's own jobs: who may read them (a token per job) and how they look to the page.

Pure bookkeeping: no I/O. The bus link feeds :class:`JobState` messages in; the app reads views out.
"""

from __future__ import annotations

import hmac
import secrets
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any

from bus.messages import JobState
from kiosk import wording

FINAL_STATES = frozenset({"done", "failed", "cancelled", "rejected"})
"""Job states after which nothing changes."""


@dataclass(frozen=True)
class KioskJob:
    """A job handed in through this kiosk."""

    job_id: str
    """Orchestrator's job id."""
    token: str
    """Secret returned to the submitting page; required to read the job."""
    session_id: str
    """Cookie session of the submitting browser."""
    label: str
    """The typed text or ``drawing (N strokes)``."""
    preview: dict[str, Any] | None
    """The planned path shown before submitting (the picture of the result)."""


def job_view(state: JobState) -> dict[str, Any]:
    """What the page is told about a job: public fields and a sentence to show."""
    metrics = None
    if state.metrics is not None:
        m = state.metrics
        metrics = {
            "rmse_pen_down_m": m.rmse_pen_down_m,
            "max_error_m": m.max_error_m,
            "iou": m.iou,
            "duration_s": m.duration_s,
        }
    return {
        "job_id": state.job_id,
        "state": state.state,
        "final": state.state in FINAL_STATES,
        "label": state.label,
        "queue_position": state.queue_position,
        "eta_s": state.eta_s,
        "vehicle_id": state.vehicle_id,
        "progress": state.progress,
        "metrics": metrics,
        "updated_at_s": state.updated_at_s,
        "status_text": wording.status_text(
            state.state,
            queue_position=state.queue_position,
            eta_s=state.eta_s,
            vehicle_id=state.vehicle_id,
            progress=state.progress,
        ),
    }


class JobBook:
    """Jobs of this kiosk and the latest state seen of any job, both bounded (oldest dropped)."""

    def __init__(self, *, max_jobs: int = 5_000, max_states: int = 5_000) -> None:
        self._jobs: OrderedDict[str, KioskJob] = OrderedDict()
        self._states: OrderedDict[str, JobState] = OrderedDict()
        self._max_jobs = max_jobs
        self._max_states = max_states

    def add(
        self, job_id: str, *, session_id: str, label: str, preview: dict[str, Any] | None
    ) -> KioskJob:
        """Record a job this kiosk submitted; returns it with a fresh token."""
        job = KioskJob(job_id, secrets.token_urlsafe(24), session_id, label, preview)
        self._jobs[job_id] = job
        self._jobs.move_to_end(job_id)
        while len(self._jobs) > self._max_jobs:
            self._jobs.popitem(last=False)
        return job

    def get(self, job_id: str) -> KioskJob | None:
        return self._jobs.get(job_id)

    def authorised(self, job_id: str, token: str | None) -> KioskJob | None:
        """The job when ``token`` is its token, else None (compared in constant time)."""
        job = self._jobs.get(job_id)
        if job is None or token is None:
            return None
        return job if hmac.compare_digest(job.token.encode(), token.encode()) else None

    def update(self, state: JobState) -> bool:
        """Remember ``state`` unless an older one; True when it changed what we knew."""
        old = self._states.get(state.job_id)
        if old is not None and (state.updated_at_s < old.updated_at_s or old == state):
            return False
        if old is not None and old.state in FINAL_STATES and state.state not in FINAL_STATES:
            return False
        self._states[state.job_id] = state
        self._states.move_to_end(state.job_id)
        while len(self._states) > self._max_states:
            self._states.popitem(last=False)
        return True

    def state(self, job_id: str) -> JobState | None:
        return self._states.get(job_id)

    def is_ours(self, job_id: str) -> bool:
        return job_id in self._jobs

"""The agent's hold on its job (pure; wall time in): may this vehicle still put ink for it?

The orchestrator takes a vehicle as lost when its token is gone, or when it has been silent, for
``policy.lost_after_s``, and gives its job to another vehicle. The agent cannot see that decision,
so it fences itself on what it can see:

- a **stall**: nothing of the agent ran for ``lost_after_s`` (the process was frozen, or
  starved): its heartbeats stopped with it, so the orchestrator has taken it as lost and the job
  may be someone else's. Checked before the next tick, before another setpoint is sent. (A
  shorter stall may or may not have cost it the job: the next report's answer, ``not_assigned``,
  says so within a second; a new holder needs far longer to take off and reach its board.)
- an **unconfirmed write**: while writing, no acknowledgement of a report of this job for
  ``lost_after_s`` (counted from the last acknowledgement, or from the start of writing). The
  service asks for one (a ``progress`` report) when a third of that has passed without any;
- a **refusal**: the orchestrator answered a report of this job with ``not_assigned``.

A fenced agent lifts the brush, gives the job up and flies home (the orchestrator puts the job
back in the queue, or has done so already); it never writes that job again. A job interrupted
this way is written from the start by whichever vehicle gets it next.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field


@dataclass
class JobLease:
    """See the module docstring; times are wall-clock [s] (monotonic)."""

    lost_after_s: float
    """The show's ``policy.lost_after_s``, [s]."""
    job_id: str | None = None
    """The job held (None: none)."""
    confirmed_at_s: float = -math.inf
    """When the orchestrator last confirmed the job: its acknowledgement arrived, [s]."""
    writing_since_s: float | None = None
    """When this job's writing began (the brush may touch from then on), [s]."""
    _last_tick_s: float | None = field(default=None, repr=False)
    _next_probe_s: float = field(default=-math.inf, repr=False)

    @property
    def stall_limit_s(self) -> float:
        """A stall this long in [s] voids the lease."""
        return self.lost_after_s

    @property
    def probe_after_s(self) -> float:
        """Ask for a confirmation when none came for this long in [s] while writing."""
        return self.lost_after_s / 3.0

    def hold(self, job_id: str | None, writing: bool, now_s: float) -> None:
        """The runner's job and whether it is writing, at this tick."""
        if job_id != self.job_id:
            self.job_id, self.confirmed_at_s, self.writing_since_s = job_id, now_s, None
        if job_id is None or not writing:
            self.writing_since_s = None
        elif self.writing_since_s is None:
            self.writing_since_s = now_s

    def acknowledged(self, job_id: str, sent_at_s: float) -> None:
        """The orchestrator acknowledged a report of ``job_id`` sent at ``sent_at_s``."""
        if job_id == self.job_id:
            self.confirmed_at_s = max(self.confirmed_at_s, sent_at_s)

    def tick(self, now_s: float) -> float:
        """The control loop starts a tick now; returns how long it did not run, [s]: since the
        end of the previous tick (time spent waiting for the backend inside a tick, e.g. for a
        take-off to be accepted, is no stall: the rest of the agent ran meanwhile)."""
        last = self._last_tick_s
        return 0.0 if last is None else now_s - last

    def tick_done(self, now_s: float) -> None:
        """The control loop finished a tick now."""
        self._last_tick_s = now_s

    def breach(self, gap_s: float, now_s: float) -> str | None:
        """Why the job must be given up now (None: it is still this vehicle's)."""
        if self.job_id is None:
            return None
        if gap_s >= self.stall_limit_s:
            return f"this agent stalled for {gap_s:.1f} s"
        if self.writing_since_s is None:
            return None
        since = max(self.confirmed_at_s, self.writing_since_s)
        if now_s - since >= self.lost_after_s:
            return f"no acknowledgement from the orchestrator for {now_s - since:.1f} s"
        return None

    def wants_probe(self, now_s: float) -> bool:
        """While writing: whether to ask for a confirmation now."""
        if self.writing_since_s is None:
            return False
        since = max(self.confirmed_at_s, self.writing_since_s)
        return now_s - since >= self.probe_after_s

    def probe_due(self, now_s: float) -> bool:
        """:meth:`wants_probe`, at most once every ``probe_after_s``: True when the service
        should send a ``progress`` report now to get a confirmation."""
        if not self.wants_probe(now_s) or now_s < self._next_probe_s:
            return False
        self._next_probe_s = now_s + self.probe_after_s
        return True

"""The agent's hold on its job (pure; wall time in): may this vehicle still put ink for it?

The orchestrator takes a vehicle as lost when its token is gone, or when it has been silent, for
``policy.lost_after_s``, and then keeps the job for it a while longer (its result may be on the
way) before giving it to another vehicle. The agent cannot see those decisions, so it fences
itself on what it can see:

- a **stall**: nothing of the agent ran for ``lost_after_s`` (the process was frozen, or
  starved): its heartbeats stopped with it, so the orchestrator has taken it as lost and the job
  may be someone else's. Checked before the next tick, before another setpoint is sent. (A
  shorter stall may or may not have cost it the job: the next report's answer, ``not_assigned``,
  says so within a second; a new holder needs far longer to take off and reach its board.)
- an **unconfirmed write**: the brush goes down only within ``lost_after_s`` of the sending of a
  *ready* report (``holding`` with the planned writing) that the orchestrator acknowledged: it
  stored the receipt (``Job.writing_since_s``) before answering, so both sides know that writing
  may have begun before either can be cut off (:meth:`JobLease.may_begin_writing`). The vehicle
  sends one when it reaches the start of its writing, again while it settles there, and writes
  on unheard until the write fence (``bus/fence.py``: the planned writing, with room for a slow
  host, after that report was sent), through a restart of the orchestrator or the router; the
  orchestrator holds the job for it until later than that (``orchestrator/holders.py``). While
  the job is flown and no acknowledgement came for a third of ``lost_after_s``, the service asks
  for one (``holding`` before writing, ``progress`` while writing); past the fence, writing
  needs one younger than ``lost_after_s``;
- an **unheard flight**: a job flown ``unheard_before_writing_s`` without any acknowledgement
  before its writing began (the orchestrator is gone for good) is given up;
- a **refusal**: the orchestrator answered a report of this job with ``not_assigned``.

A fenced agent lifts the brush, gives the job up and flies home (the orchestrator puts the job
back in the queue, or has done so already); it never writes that job again. A job interrupted
this way is written from the start by whichever vehicle gets it next.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from bus.fence import unheard_writing_s


@dataclass
class JobLease:
    """See the module docstring; times are wall-clock [s] (monotonic)."""

    lost_after_s: float
    """The show's ``policy.lost_after_s``, [s]."""
    time_scale: float = 1.0
    """Show (agent) seconds per wall second."""
    unheard_before_writing_s: float = 10.0
    """Give a job up that has gone this long in wall [s] unacknowledged before its writing began:
    the orchestrator is gone for good (under ``skyquill up``'s supervisor it is back in 1-3 s)."""
    job_id: str | None = None
    """The job held (None: none)."""
    confirmed_at_s: float = -math.inf
    """When the orchestrator last confirmed the job: the sending of a report it acknowledged, or
    the assignment's arrival, [s]."""
    active: bool = False
    """The job is being flown (from preflight to the end of writing): confirmations are asked."""
    writing: bool = False
    """The job is being written: the brush may touch."""
    ready_at_s: float = -math.inf
    """When the latest *ready* report of the job the orchestrator acknowledged was sent, [s]."""
    fence_at_s: float | None = None
    """Until when the job may be written unheard, [s] (a ready report acknowledged); None: only
    ``lost_after_s`` after the last confirmation."""
    _last_tick_s: float | None = field(default=None, repr=False)
    _next_probe_s: float = field(default=-math.inf, repr=False)
    _next_ready_s: float = field(default=-math.inf, repr=False)

    @property
    def stall_limit_s(self) -> float:
        """A stall this long in [s] voids the lease."""
        return self.lost_after_s

    @property
    def probe_after_s(self) -> float:
        """Ask for a confirmation when none came for this long in [s] while active."""
        return self.lost_after_s / 3.0

    def hold(self, job_id: str | None, *, active: bool, writing: bool, now_s: float) -> None:
        """The runner's job, whether it is being flown and whether written, at this tick."""
        if job_id != self.job_id:
            self.job_id, self.confirmed_at_s, self.fence_at_s = job_id, now_s, None
            self.ready_at_s = self._next_probe_s = self._next_ready_s = -math.inf
        held = job_id is not None
        self.active, self.writing = held and active, held and writing

    def acknowledged(
        self, job_id: str, sent_at_s: float, ready_writing_s: float | None = None
    ) -> None:
        """The orchestrator acknowledged a report of ``job_id`` sent at ``sent_at_s``;
        ``ready_writing_s``: it was a ready report, with this planned writing in show [s] (the
        orchestrator stored its receipt, later than ``sent_at_s``, as its own fence's start)."""
        if job_id != self.job_id:
            return
        self.confirmed_at_s = max(self.confirmed_at_s, sent_at_s)
        if ready_writing_s is not None:
            self.ready_at_s = max(self.ready_at_s, sent_at_s)
            unheard_s = unheard_writing_s(ready_writing_s, self.time_scale, self.lost_after_s)
            self.fence_at_s = max(self.fence_at_s or -math.inf, sent_at_s + unheard_s)

    def may_begin_writing(self, now_s: float) -> bool:
        """Whether the brush may go down for the job now: a ready report sent less than
        ``lost_after_s`` ago was acknowledged."""
        return now_s - self.ready_at_s < self.lost_after_s

    def ready_due(self, now_s: float) -> bool:
        """While the vehicle waits at the start of its writing: whether to send a ready report
        now (none acknowledged for a third of ``lost_after_s``; at most that often)."""
        if now_s - self.ready_at_s < self.probe_after_s or now_s < self._next_ready_s:
            return False
        self._next_ready_s = now_s + self.probe_after_s
        return True

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
        unconfirmed_s = now_s - self.confirmed_at_s
        fenced = self.fence_at_s is not None and now_s < self.fence_at_s
        if self.writing and unconfirmed_s >= self.lost_after_s and not fenced:
            past = "" if self.fence_at_s is None else " and past its write fence"
            return f"no acknowledgement from the orchestrator for {unconfirmed_s:.1f} s{past}"
        if self.active and not self.writing and unconfirmed_s >= self.unheard_before_writing_s:
            return f"no acknowledgement from the orchestrator for {unconfirmed_s:.1f} s"
        return None

    def wants_probe(self, now_s: float) -> bool:
        """While active: whether to ask for a confirmation now."""
        return self.active and now_s - self.confirmed_at_s >= self.probe_after_s

    def probe_due(self, now_s: float) -> bool:
        """:meth:`wants_probe`, at most once every ``probe_after_s``: True when the service
        should send a report now to get a confirmation."""
        if not self.wants_probe(now_s) or now_s < self._next_probe_s:
            return False
        self._next_probe_s = now_s + self.probe_after_s
        return True

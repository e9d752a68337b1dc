"""How long a vehicle may go on writing a job while nobody acknowledges it (the write fence).

Only the orchestrator assigns jobs, and it keeps its jobs in SQLite; but while it restarts, or
while the router does, or while a vehicle is cut off, the vehicle writing a job hears nothing.
Both sides bound that time with the same figures, each on its own clock (only durations are
compared, so the two clocks need not agree; a Unix clock stepped back by NTP shortens the
orchestrator's margin by the step):

- the **agent** (``vehicle_agent/lease.py``) lowers the brush only within ``lost_after_s`` of
  sending a *ready* report (``holding`` with the planned writing) that the orchestrator
  acknowledged, and writes on unheard until :func:`unheard_writing_s` after the latest such
  report was sent; without one, it does not write at all;
- the **orchestrator** (``orchestrator/holders.py``) stores the receipt of each ready report
  before acknowledging it (``Job.writing_since_s``, the latest one, which came after the agent's
  latest acknowledged one was sent), and gives the job to nobody else until the vehicle is heard
  again, or the operator has put a fresh sheet on its board, which it accepts only
  :func:`unheard_writing_s` plus ``lost_job_hold_s`` after it.

So every moment the old holder may still ink lies before the moment anyone else may be given the
job, by at least ``lost_job_hold_s``, under any interleaving of restarts, losses and delays;
and a new holder needs tens of seconds more to take off and reach its board. And once the brush
is down, both sides know it may be: an outage of the orchestrator or the router from then on,
shorter than the fence, costs the writer nothing (``started`` and ``progress`` are told after).
"""

from __future__ import annotations

WRITING_SLOWDOWN = 0.5
"""How much longer than planned, as a fraction, writing may take in wall time: the agent's loop
follows the plan in its own time, which falls behind the wall clock when its host is loaded (the
fleet host benchmark measured real-time factors 0.965-1.0 on 2 cores, ``docs/
fleet_host_measurements.md``); 0.5 leaves room for far worse. Not from the papers."""


def unheard_writing_s(planned_writing_s: float, time_scale: float, lost_after_s: float) -> float:
    """How long in wall [s] after its ready report a vehicle may write a job unheard.

    ``planned_writing_s``: the planned writing in show time [s]; ``time_scale``: show seconds per
    wall second; ``lost_after_s``: the show's ``policy.lost_after_s`` [s]."""
    return lost_after_s + (1.0 + WRITING_SLOWDOWN) * planned_writing_s / time_scale

"""The agent's clock against the orchestrator's, measured as NTP measures it (RFC 5905).

Which clocks: the two machines' wall clocks (``time.time()``, Unix time), the clocks that stamp
the event log, the recordings and the telemetry. Not the agent's control clock
(``vehicle_agent/clock.py``, which runs at the show's time scale) nor a monotonic clock: the
question is whether the machines' clocks agree, which NTP or PTP on each host should ensure.

One exchange (RFC 5905, section 8, "on-wire protocol"): the agent notes ``t1`` on its clock and
queries ``orchestrator/clock`` (``bus.keys.ShowKeys.clock``); the orchestrator stamps ``t2`` when
the query comes and ``t3`` when it replies, on its clock (``bus.messages.ClockReply``); the agent
notes ``t4`` when the reply comes. Then

    theta = ((t2 - t1) + (t3 - t4)) / 2    the orchestrator's clock minus the agent's
    delta = (t4 - t1) - (t3 - t2)          the round trip, the orchestrator's own time taken out

and the offset the agent keeps (``ClockSample.offset_s``, the preflight's reading) is ``-theta``:
its own clock minus the orchestrator's, positive when the agent's clock is ahead. However the
round trip splits between the way there and the way back, the true offset is within
``delta / 2`` of the estimate: a one-way delay is all the formula cannot see. What the agent's
event loop adds before it reads ``t4`` (the reply poller's period, other tasks) is part of
``delta`` and so within that bound too.

As NTP's clock filter does, the agent keeps the latest few samples and trusts the one of least
delay (:class:`ClockFilter`): a query that waited in a queue on its way gives a larger delay and a
worse offset, and is outvoted rather than raising a false alarm. It measures at start (a short
burst, as NTP's ``iburst``, so the filter is full within seconds) and then about every
``period_s`` (:class:`ClockSync`); the service sets ``runner.clock_offset_s`` from the best
sample, which the preflight checks (``vehicle_agent/preflight.py``) and the status reports
(``clock_offset_ms``).
"""

from __future__ import annotations

import asyncio
import logging
import random
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

from bus.keys import ShowKeys
from bus.messages import ClockReply
from bus.rpc import aquery_one
from bus.session import BusError, Session

log = logging.getLogger(__name__)

FILTER_SAMPLES = 4
"""Samples the filter chooses from. NTP's clock filter keeps 8 at poll intervals of 64 s and
more; on a show's LAN a round trip takes about a millisecond and only the odd query waits in a
queue, so 4 (40 s at the default period) ride those out, and a clock put right is trusted
again within 40 s rather than 80."""
PERIOD_S = 10.0
"""Wall time in [s] between two exchanges after the start (each one drawn within 10 % of it,
so the vehicles of a fleet host do not all ask at once)."""
BURST = FILTER_SAMPLES
"""Exchanges at start, ``BURST_GAP_S`` apart."""
BURST_GAP_S = 0.5
"""Wall time in [s] between two exchanges of the start burst."""
TIMEOUT_S = 2.0
"""Wall time in [s] an exchange waits for its reply (no reply: no sample)."""


@dataclass(frozen=True)
class ClockSample:
    """One exchange's estimate."""

    offset_s: float
    """The agent's clock minus the orchestrator's in [s] (NTP's ``-theta``)."""
    delay_s: float
    """Round trip in [s], the orchestrator's own time taken out (NTP's ``delta``): the true
    offset is within ``delay_s / 2`` of ``offset_s``."""


def on_wire(t1_s: float, t2_s: float, t3_s: float, t4_s: float) -> ClockSample:
    """The sample of one exchange (RFC 5905's on-wire formulas): ``t1_s`` the agent sent the
    query and ``t4_s`` it got the reply (its clock), ``t2_s`` the orchestrator got the query and
    ``t3_s`` it replied (its clock); all Unix times in [s]."""
    theta_s = ((t2_s - t1_s) + (t3_s - t4_s)) / 2.0
    delta_s = (t4_s - t1_s) - (t3_s - t2_s)
    return ClockSample(offset_s=-theta_s, delay_s=delta_s)


class ClockFilter:
    """The latest ``size`` samples; the best is the one of least delay (NTP's clock filter)."""

    def __init__(self, size: int = FILTER_SAMPLES) -> None:
        self._samples: deque[ClockSample] = deque(maxlen=size)

    def add(self, sample: ClockSample) -> ClockSample | None:
        """Keep ``sample`` (not one of negative delay: a clock was set during its exchange, its
        figures mean nothing); the best sample now."""
        if sample.delay_s >= 0.0:
            self._samples.append(sample)
        return self.best

    @property
    def best(self) -> ClockSample | None:
        """The kept sample of least delay; None before the first."""
        return min(self._samples, key=lambda s: s.delay_s, default=None)


class ClockSync:
    """Measures the agent's clock against the orchestrator's on the bus (module docstring)."""

    def __init__(
        self,
        keys: ShowKeys,
        *,
        wall_clock: Callable[[], float] = time.time,
        period_s: float = PERIOD_S,
    ) -> None:
        self.keys = keys
        self.wall_clock = wall_clock
        """The agent's wall clock, Unix time in [s] (injected: tests shift it)."""
        self.period_s = period_s
        self.filter = ClockFilter()

    async def exchange(self, session: Session) -> ClockSample | None:
        """One exchange; None when the orchestrator did not answer (it is away, or restarting)."""
        t1_s = self.wall_clock()
        try:
            reply = await aquery_one(
                session, self.keys.clock, None, ClockReply, timeout_s=TIMEOUT_S
            )
        except BusError as exc:  # no reply: the orchestrator is away
            log.debug("clock exchange on %s: %s", self.keys.clock, exc)
            return None
        except Exception as exc:  # a failed measurement never stops the agent
            log.warning("clock exchange on %s failed: %s", self.keys.clock, exc)
            return None
        t4_s = self.wall_clock()
        return on_wire(t1_s, reply.receive_s, reply.transmit_s, t4_s)

    async def run(self, session: Session, on_best: Callable[[ClockSample], None]) -> None:
        """Measure at start and then every ``period_s`` or so, for ever; ``on_best`` gets the
        filter's best sample after each exchange answered."""
        for n in range(BURST):
            if n:
                await asyncio.sleep(BURST_GAP_S)
            await self._measure(session, on_best)
        while True:
            await asyncio.sleep(self.period_s * random.uniform(0.9, 1.1))
            await self._measure(session, on_best)

    async def _measure(self, session: Session, on_best: Callable[[ClockSample], None]) -> None:
        sample = await self.exchange(session)
        best = self.filter.add(sample) if sample is not None else None
        if best is not None:
            on_best(best)

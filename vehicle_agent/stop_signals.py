"""How an agent process stops: a vehicle in the air lands before its agent leaves.

SIGTERM or SIGINT (``skyquill down``, a supervisor stopping its children, a supervisor that
died with ``PR_SET_PDEATHSIG``, ``kill``, a Ctrl-C in the agent's own terminal): a vehicle in
the air lands first (:meth:`vehicle_agent.service.AgentService.land_then_stop`; a fleet host's
vehicles all together), then the agent stops; one on the ground stops at once. On a real
vehicle stopping the agent only closes its MAVLink link and leaves the autopilot to its
failsafe, wherever it is: so no stop of the process leaves a vehicle in the air unless asked
to. A second SIGTERM or SIGINT, or :data:`NOW_SIGNAL` (``skyquill down --now``, a hurried stop
of the demo), stops at once without landing.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import signal
from typing import Protocol

log = logging.getLogger(__name__)

NOW_SIGNAL = signal.SIGUSR1
"""Stop at once, without landing (``skyquill down --now``)."""
LAND_LIMIT_S = 45.0
"""Longest a landing before the agent stops may take, wall [s]: under the supervisor's limit
for a child still busy stopping (``cli/supervisor.py``, ``ChildSpec.stop_limit_s``, 60 s), which
kills it. From mid-character, the return and the descent took 7.6 s of flight in the
in-process sim and 14 s over MAVLink to the project's simulated autopilot (solo show,
``tests/test_down_lands.py``); the rest is room for a larger venue and a slow autopilot."""


class LandsFirst(Protocol):
    """Runs until its stop event is set, and can land first: an agent's service
    (:class:`vehicle_agent.service.AgentService`), a fleet host's vehicles together
    (:class:`vehicle_agent.fleet.FleetHost`)."""

    async def run(self, stop: asyncio.Event) -> None: ...

    async def land_then_stop(self, stop: asyncio.Event, limit_s: float) -> None:
        """Set ``stop`` once its vehicles are on the ground, or after ``limit_s`` wall [s]."""
        ...


async def run_landing_first(service: LandsFirst, limit_s: float = LAND_LIMIT_S) -> None:
    """Run ``service`` until a stop signal (see the module docstring)."""
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    landing: list[asyncio.Task[None]] = []

    def asked_to_stop() -> None:
        if stop.is_set():
            return
        if landing:  # the second time: at once
            now()
            return
        landing.append(loop.create_task(service.land_then_stop(stop, limit_s)))

    def now() -> None:
        if not stop.is_set():
            log.warning("stopping at once, without landing")
            stop.set()

    for sig in (signal.SIGINT, signal.SIGTERM):
        with contextlib.suppress(NotImplementedError):
            loop.add_signal_handler(sig, asked_to_stop)
    with contextlib.suppress(NotImplementedError):
        loop.add_signal_handler(NOW_SIGNAL, now)
    try:
        await service.run(stop)
    finally:
        for task in landing:
            task.cancel()

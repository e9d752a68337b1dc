"""Running a service until the process is told to stop (SIGINT, SIGTERM)."""

from __future__ import annotations

import asyncio
import contextlib
import signal
from typing import Protocol


class Stoppable(Protocol):
    """Runs until its stop event is set (an agent's service, a fleet host)."""

    async def run(self, stop: asyncio.Event) -> None: ...


async def run_until_signalled(runner: Stoppable) -> None:
    """Run ``runner`` until SIGINT or SIGTERM."""
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):
        with contextlib.suppress(NotImplementedError):
            loop.add_signal_handler(sig, stop.set)
    await runner.run(stop)

"""Entry points: run one show's orchestrator until SIGINT/SIGTERM (``skyquill orchestrator``)."""

from __future__ import annotations

import asyncio
import contextlib
import functools
import logging
import signal
import time
from pathlib import Path

from bus.keys import ShowKeys
from bus.recorder import McapRecorder
from bus.session import Role, open_session
from orchestrator.disk_room import DiskReserve
from orchestrator.recordings import prune_recordings
from orchestrator.service import OrchestratorService, recording_path
from orchestrator.store import JobStore
from scene.show_scene import ShowScene
from showfile import Show
from trust.settings import session_settings

log = logging.getLogger(__name__)


async def serve_show(
    show: Show,
    *,
    role: Role = "client",
    stop: asyncio.Event | None = None,
    ready: asyncio.Event | None = None,
) -> None:
    """Open the session, the database and the recording; serve until ``stop`` is set.

    ``role="router"`` also hosts the show's Zenoh router (listening on ``zenoh.router_listen``),
    for a one-process set-up; under ``skyquill up`` the orchestrator is a client of its router.
    """
    stop = stop or asyncio.Event()
    with contextlib.ExitStack() as stack:
        identity = "router" if role == "router" else "orchestrator"
        session = stack.enter_context(open_session(session_settings(show, identity), role=role))
        reserve = DiskReserve(show.database_path)
        if not reserve.make(show.storage.min_free_mb * 1e6):
            log.warning("no room for the disk reserve beside %s", show.database_path)
        store = stack.enter_context(JobStore(show.database_path, reserve))
        recorder = None
        if show.storage.record:
            path = recording_path(show, time.time())
            recorder = stack.enter_context(
                McapRecorder(
                    path,
                    ShowKeys(show.show_id),
                    max_file_bytes=int(show.storage.recording_part_mb * 1e6),
                    on_part_done=functools.partial(_prune, show),
                    derive=ShowScene(show).derive if show.storage.record_scene else None,
                )
            )
            log.info("recording the bus to %s", path)
        service = OrchestratorService(show, session, store, recorder=recorder)
        if ready is not None:
            ready.set()
        await service.run(stop)


def _prune(show: Show, finished: Path, begun: Path) -> None:
    """Keep the show's recordings within budget once a part is finished."""
    budget = int(show.storage.recordings_budget_mb * 1e6)
    for path in prune_recordings(show.recordings_dir, show.show_id, budget, (finished, begun)):
        log.info("recording %s removed (recordings over %g MB)", path.name, budget / 1e6)


def run_orchestrator(show: Show, *, role: Role = "client") -> int:
    """Blocking: serve ``show`` until SIGINT or SIGTERM; returns the exit status."""

    async def main() -> None:
        stop = asyncio.Event()
        loop = asyncio.get_running_loop()
        for sig in (signal.SIGINT, signal.SIGTERM):
            with contextlib.suppress(NotImplementedError, RuntimeError):
                loop.add_signal_handler(sig, stop.set)
        await serve_show(show, role=role, stop=stop)

    asyncio.run(main())
    return 0

"""The kiosk's link to the orchestrator over the bus: submit, and follow job states.

Job states arrive on ``jobs/*`` (every change) and in the 1 Hz ``fleet`` snapshot (queue positions
and ETAs that move as other jobs finish). Zenoh's threads push them into a FIFO channel; one task in
the event loop applies them to the :class:`JobBook` and wakes the pages watching those jobs.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Iterator
from typing import Any

from bus.bridge import ChannelClosedError, FifoChannel, RingChannel
from bus.keys import ShowKeys
from bus.messages import JobState, ShowSnapshot, SubmitReply, SubmitRequest
from bus.pubsub import subscribe
from bus.rpc import NoReplyError, RemoteError, aquery_one
from bus.session import Session
from kiosk.errors import KioskError
from kiosk.jobs import JobBook

log = logging.getLogger(__name__)


class OrchestratorUnavailableError(KioskError):
    """The orchestrator did not answer (not running, or the bus is down)."""


class OrchestratorLink:
    """Submits to the orchestrator's ``submit`` queryable and follows ``jobs/<id>``."""

    def __init__(
        self, session: Session, keys: ShowKeys, book: JobBook, *, timeout_s: float = 5.0
    ) -> None:
        self._session = session
        self._keys = keys
        self.book = book
        """Jobs of this kiosk and the newest state seen of each job."""
        self._timeout_s = timeout_s
        self._watchers: dict[str, set[RingChannel[JobState]]] = {}
        self._inbox: FifoChannel[JobState] | None = None
        self._subscribers: list[Any] = []
        self._task: asyncio.Task[None] | None = None

    async def start(self) -> None:
        """Subscribe to job states; call inside the running event loop."""
        inbox: FifoChannel[JobState] = FifoChannel()
        self._inbox = inbox

        def on_job(_key: str, state: JobState) -> None:
            inbox.push(state)

        def on_fleet(_key: str, snapshot: ShowSnapshot) -> None:
            for state in snapshot.jobs:
                inbox.push(state)

        self._subscribers = [
            subscribe(self._session, self._keys.jobs_all, JobState, on_job),
            subscribe(self._session, self._keys.fleet, ShowSnapshot, on_fleet),
        ]
        self._task = asyncio.create_task(self._pump(inbox), name="kiosk-job-states")

    async def close(self) -> None:
        """Undeclare subscribers and stop the pump."""
        for sub in self._subscribers:
            with contextlib.suppress(Exception):
                sub.undeclare()
        self._subscribers = []
        if self._inbox is not None:
            self._inbox.close()
        if self._task is not None:
            with contextlib.suppress(asyncio.CancelledError):
                await self._task

    async def _pump(self, inbox: FifoChannel[JobState]) -> None:
        while True:
            try:
                state = await inbox.get()
            except ChannelClosedError:
                return
            self.apply(state)

    def apply(self, state: JobState) -> None:
        """Record a job state and wake the pages watching it (event-loop thread)."""
        if self.book.update(state):
            for channel in self._watchers.get(state.job_id, ()):
                channel.push(state)

    @contextlib.contextmanager
    def watch(self, job_id: str) -> Iterator[RingChannel[JobState]]:
        """A channel of this job's new states while the ``with`` block lasts."""
        channel: RingChannel[JobState] = RingChannel(8)
        self._watchers.setdefault(job_id, set()).add(channel)
        try:
            yield channel
        finally:
            watchers = self._watchers.get(job_id)
            if watchers is not None:
                watchers.discard(channel)
                if not watchers:
                    del self._watchers[job_id]

    def end_streams(self) -> None:
        """Close every watcher channel so open status streams finish (server shutdown)."""
        for watchers in list(self._watchers.values()):
            for channel in list(watchers):
                channel.close()

    @property
    def watcher_count(self) -> int:
        """Open status streams (for health checks and tests)."""
        return sum(len(w) for w in self._watchers.values())

    async def submit(self, request: SubmitRequest) -> SubmitReply:
        """The orchestrator's answer; :class:`OrchestratorUnavailableError` if nobody answers."""
        try:
            return await aquery_one(
                self._session, self._keys.submit, request, SubmitReply, timeout_s=self._timeout_s
            )
        except NoReplyError as exc:
            raise OrchestratorUnavailableError(str(exc)) from exc
        except RemoteError as exc:
            return SubmitReply(ok=False, error=exc.info)

    async def fetch(self, job_id: str) -> JobState | None:
        """The job's state from the orchestrator's snapshot; None if absent or no answer."""
        try:
            snapshot = await aquery_one(
                self._session, self._keys.snapshot, None, ShowSnapshot, timeout_s=self._timeout_s
            )
        except (NoReplyError, RemoteError) as exc:
            log.warning("snapshot query failed: %s", exc)
            return None
        for job in snapshot.jobs:
            self.apply(job)
        return self.book.state(job_id)

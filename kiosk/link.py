"""The kiosk's link to the orchestrator over the bus: submit, and follow job states.

Job states arrive on ``jobs/*`` (every change) and in the 1 Hz ``fleet`` snapshot (queue positions
and ETAs that move as other jobs finish). Zenoh's threads push them into a FIFO channel; one task in
the event loop applies them to the :class:`JobBook` and wakes the pages watching those tickets.
The time of the last ``fleet`` snapshot says whether what the pages show is current. The ``fleet``
snapshot lists no finished job: a job a page follows that is neither finished here nor listed
there has ended unheard (its last ``jobs/<id>`` message lost, e.g. across a reconnection), and
its final state is asked of the orchestrator's ``snapshot`` (:meth:`OrchestratorLink._catch_up`).

A submission whose first try gets no answer stays pending: :meth:`OrchestratorLink.follow_up`
sends it again with the same idempotency key (so it becomes at most one job) until the
orchestrator answers, then binds the job to the ticket or records the refusal.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Callable, Iterator
from typing import Any

from bus.bridge import ChannelClosedError, FifoChannel, RingChannel
from bus.keys import ShowKeys
from bus.messages import JobState, ShowSnapshot, SubmitReply, SubmitRequest
from bus.pubsub import subscribe
from bus.rpc import NoReplyError, RemoteError, aquery_one
from bus.session import Session
from kiosk.errors import KioskError
from kiosk.jobs import FINAL_STATES, JobBook

log = logging.getLogger(__name__)

KIOSK_IDENTITY = "kiosk"
"""The kiosk's certificate's common name (``trust/acl.py``)."""
RETRY_DELAYS_S = (0.5, 1.0, 2.0, 4.0, 8.0)
"""Pauses between tries of a pending submission; the last one repeats until an answer."""


class OrchestratorUnavailableError(KioskError):
    """The orchestrator did not answer (not running, or the bus is down)."""


class OrchestratorLink:
    """Submits to the orchestrator's ``submit/kiosk`` queryable and follows ``jobs/<id>``."""

    def __init__(
        self,
        session: Session,
        keys: ShowKeys,
        book: JobBook,
        *,
        timeout_s: float = 5.0,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self._session = session
        self._keys = keys
        self._submit_key = keys.submit_as(KIOSK_IDENTITY)
        """The kiosk's own submit key: the orchestrator counts the kiosk's quota by it."""
        self.book = book
        """Tickets of this kiosk and the newest state seen of each job."""
        self._timeout_s = timeout_s
        self._clock = clock
        self.fleet_seen_s: float | None = None
        """``clock()`` when the last ``fleet`` snapshot arrived (None: never)."""
        self._started_s = clock()
        self._watchers: dict[str, set[RingChannel[str]]] = {}
        """Ticket -> channels of the pages following it (woken with the ticket)."""
        self._follow_ups: set[asyncio.Task[None]] = set()
        self._paused_seen = False
        """Whether the latest ``fleet`` snapshot had the queue paused (Zenoh's thread writes)."""
        self._inbox: FifoChannel[JobState | frozenset[str]] | None = None
        self._asking: set[str] = set()
        """Jobs whose final state is being asked for (one ask at a time per job)."""
        self._subscribers: list[Any] = []
        self._task: asyncio.Task[None] | None = None

    async def start(self) -> None:
        """Subscribe to job states; call inside the running event loop."""
        inbox: FifoChannel[JobState | frozenset[str]] = FifoChannel()
        self._inbox = inbox

        def on_job(_key: str, state: JobState) -> None:
            inbox.push(state)

        def on_fleet(_key: str, snapshot: ShowSnapshot) -> None:
            for state in snapshot.jobs:
                inbox.push(state)
            self._paused_seen = snapshot.queue_paused  # read with the marker below
            # marks the snapshot's arrival (fresh news of the orchestrator), with what it lists
            inbox.push(frozenset(state.job_id for state in snapshot.jobs))

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
        for task in list(self._follow_ups):
            task.cancel()
        if self._task is not None:
            with contextlib.suppress(asyncio.CancelledError):
                await self._task

    async def _pump(self, inbox: FifoChannel[JobState | frozenset[str]]) -> None:
        while True:
            try:
                item = await inbox.get()
            except ChannelClosedError:
                return
            if isinstance(item, frozenset):
                self.fleet_seen_s = self._clock()
                self._follow_pause(self._paused_seen)
                self._catch_up(item)
            else:
                self.apply(item)

    def _catch_up(self, listed: frozenset[str]) -> None:
        """Ask for the final state of every job a page follows that is not finished here and
        not ``listed`` in the ``fleet`` snapshot (which lists no finished job)."""
        for ticket in self._watchers:
            job = self.book.get(ticket)
            if job is None or job.job_id is None:
                continue
            states = self.book.characters(job) if job.phrase_size else [self.book.state(job.job_id)]
            for state in states:
                if state is None or state.state in FINAL_STATES or state.job_id in listed:
                    continue
                if state.job_id not in self._asking:
                    self._asking.add(state.job_id)
                    task = asyncio.create_task(self._ask_final(state.job_id))
                    self._follow_ups.add(task)
                    task.add_done_callback(self._follow_ups.discard)

    async def _ask_final(self, job_id: str) -> None:
        try:
            await self.fetch(job_id)
        finally:
            self._asking.discard(job_id)

    def stale(self, max_age_s: float) -> bool:
        """No ``fleet`` snapshot for ``max_age_s`` [s], counted from the link's start until the
        first: the orchestrator or the bus is down. A kiosk just started has missed nothing yet;
        said stale until its first snapshot, it told the first visitors "the show is slow to
        answer" as their first ticket went in (a fresh-clone CI run, tests/test_kiosk_browser_
        truth.py)."""
        seen = self._started_s if self.fleet_seen_s is None else self.fleet_seen_s
        return self._clock() - seen > max_age_s

    def apply(self, state: JobState) -> None:
        """Record a job state and wake the pages watching it (event-loop thread)."""
        if self.book.update(state):
            ticket = self.book.ticket_of(state.job_id)
            if ticket is not None:
                self.wake(ticket)

    def _follow_pause(self, paused: bool) -> None:
        """The show's queue paused or resumed: every page following a ticket says so."""
        if paused == self.book.show_paused:
            return
        self.book.show_paused = paused
        for ticket in list(self._watchers):
            self.wake(ticket)

    def wake(self, ticket: str) -> None:
        """Tell the pages following ``ticket`` that it changed."""
        for channel in self._watchers.get(ticket, ()):
            channel.push(ticket)

    @contextlib.contextmanager
    def watch(self, ticket: str) -> Iterator[RingChannel[str]]:
        """A channel woken at each change of the ticket while the ``with`` block lasts."""
        channel: RingChannel[str] = RingChannel(8)
        self._watchers.setdefault(ticket, set()).add(channel)
        try:
            yield channel
        finally:
            watchers = self._watchers.get(ticket)
            if watchers is not None:
                watchers.discard(channel)
                if not watchers:
                    del self._watchers[ticket]

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
                self._session, self._submit_key, request, SubmitReply, timeout_s=self._timeout_s
            )
        except NoReplyError as exc:
            raise OrchestratorUnavailableError(str(exc)) from exc
        except RemoteError as exc:
            # The orchestrator answers refusals as SubmitReply; an error reply comes from the
            # transport (e.g. Zenoh's "Timeout"): the request may still be processed later.
            raise OrchestratorUnavailableError(str(exc)) from exc

    def follow_up(
        self, ticket: str, request: SubmitRequest, on_reply: Callable[[str, SubmitReply], None]
    ) -> None:
        """Send ``request`` again (same idempotency key) until answered; then ``on_reply``."""
        task = asyncio.create_task(self._retry(ticket, request, on_reply), name=f"retry-{ticket}")
        self._follow_ups.add(task)
        task.add_done_callback(self._follow_ups.discard)

    async def _retry(
        self, ticket: str, request: SubmitRequest, on_reply: Callable[[str, SubmitReply], None]
    ) -> None:
        tries = 0
        while self.book.get(ticket) is not None:
            await asyncio.sleep(RETRY_DELAYS_S[min(tries, len(RETRY_DELAYS_S) - 1)])
            tries += 1
            try:
                reply = await self.submit(request)
            except OrchestratorUnavailableError:
                continue
            on_reply(ticket, reply)
            self.wake(ticket)
            return

    async def fetch(self, job_id: str) -> JobState | None:
        """The job's state from the orchestrator's snapshot; None if absent or no answer."""
        try:
            snapshot = await aquery_one(
                self._session, self._keys.snapshot, None, ShowSnapshot, timeout_s=self._timeout_s
            )
        except (NoReplyError, RemoteError) as exc:
            log.warning("snapshot query failed: %s", exc)
            return None
        self.fleet_seen_s = self._clock()
        for job in snapshot.jobs:
            self.apply(job)
        return self.book.state(job_id)

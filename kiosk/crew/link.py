"""The crew page's link to the orchestrator: the kiosk's second Zenoh session, opened with the
crew's certificate (identity ``crew``), never the public's.

It follows the ``fleet`` snapshot (about 1 Hz, and on every change) for the boards and vehicles
waiting for the crew, and sends the crew's confirmations on ``orchestrator/command/crew``: the
router lets only the crew's certificate query that key, so the orchestrator knows the sender
from the key, as for outside operators, and takes ``fresh_sheet`` and ``battery_swapped`` from it
and nothing else. The phone that tapped is named in ``operator`` (``crew (deck-1)`` in the log).
"""

from __future__ import annotations

import asyncio
import contextlib
import time
from collections.abc import Callable, Iterator, Mapping
from typing import Any

from bus.bridge import ChannelClosedError, RingChannel
from bus.keys import ShowKeys
from bus.messages import CommandReply, ErrorInfo, OperatorCommand, ShowSnapshot
from bus.pubsub import subscribe
from bus.rpc import NoReplyError, RemoteError, aquery_one
from bus.session import Session
from kiosk.crew.tasks import CrewCommand, CrewTask, crew_tasks

CREW_IDENTITY = "crew"
"""The crew certificate's common name (``trust/acl.py``)."""


class CrewLink:
    """The crew's tasks as the orchestrator last published them, and its confirmations."""

    def __init__(
        self,
        session: Session,
        keys: ShowKeys,
        places: Mapping[str, int],
        *,
        timeout_s: float = 5.0,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self._session = session
        self._command_key = keys.command_as(CREW_IDENTITY)
        self._fleet_key = keys.fleet
        self._places = dict(places)
        self._timeout_s = timeout_s
        self._clock = clock
        self.tasks: list[CrewTask] = []
        """What the crew has to do, as of the latest snapshot."""
        self.confirmed: set[tuple[str, str]] = set()
        """Tasks confirmed here that the orchestrator still lists (a battery until its fresh
        pack reports): shown as done, not offered again."""
        self.seen_s: float | None = None
        """``clock()`` when the latest snapshot arrived (None: never)."""
        self._inbox: RingChannel[ShowSnapshot] | None = None
        self._watchers: set[RingChannel[bool]] = set()
        self._subscriber: Any = None
        self._task: asyncio.Task[None] | None = None

    async def start(self) -> None:
        """Follow the fleet; call inside the running event loop."""
        inbox: RingChannel[ShowSnapshot] = RingChannel(1)  # the newest snapshot is all it needs
        self._inbox = inbox
        self._subscriber = subscribe(
            self._session, self._fleet_key, ShowSnapshot, lambda _k, snap: inbox.push(snap)
        )
        self._task = asyncio.create_task(self._pump(inbox), name="kiosk-crew-fleet")

    async def close(self) -> None:
        if self._subscriber is not None:
            with contextlib.suppress(Exception):
                self._subscriber.undeclare()
        if self._inbox is not None:
            self._inbox.close()
        if self._task is not None:
            with contextlib.suppress(asyncio.CancelledError):
                await self._task
        self.end_streams()

    async def _pump(self, inbox: RingChannel[ShowSnapshot]) -> None:
        while True:
            try:
                snapshot = await inbox.get()
            except ChannelClosedError:
                return
            self.seen(snapshot)

    def seen(self, snapshot: ShowSnapshot) -> None:
        """A snapshot arrived: the tasks it lists; the pages are woken when they changed."""
        self.seen_s = self._clock()
        tasks = crew_tasks(snapshot, self._places)
        self.confirmed &= {task.key for task in tasks}
        if tasks != self.tasks:
            self.tasks = tasks
            self._wake()

    def stale(self, max_age_s: float) -> bool:
        """No snapshot for ``max_age_s``: the orchestrator or the bus is away."""
        return self.seen_s is None or self._clock() - self.seen_s > max_age_s

    def view(self) -> list[dict[str, object]]:
        """The tasks as the page shows them."""
        return [task.to_json(task.key in self.confirmed) for task in self.tasks]

    async def confirm(self, command: CrewCommand, target: str, phone: str) -> CommandReply:
        """Send the crew's confirmation; the orchestrator's reply (``unavailable`` if none)."""
        sheet = command == "fresh_sheet"
        request = OperatorCommand(
            command=command,
            operator=phone,
            board_id=target if sheet else None,
            vehicle_id=None if sheet else target,
        )
        try:
            reply = await aquery_one(
                self._session, self._command_key, request, CommandReply, timeout_s=self._timeout_s
            )
        except (NoReplyError, RemoteError) as exc:
            info = ErrorInfo(code="unavailable", message=f"the orchestrator did not answer: {exc}")
            return CommandReply(ok=False, message=info.message, error=info)
        if reply.ok:
            self.confirmed.add((command, target))
            self._wake()
        return reply

    def _wake(self) -> None:
        for channel in list(self._watchers):
            channel.push(True)

    @contextlib.contextmanager
    def watch(self) -> Iterator[RingChannel[bool]]:
        """A channel woken at each change of the tasks while the ``with`` block lasts."""
        channel: RingChannel[bool] = RingChannel(1)
        self._watchers.add(channel)
        try:
            yield channel
        finally:
            self._watchers.discard(channel)

    def end_streams(self) -> None:
        """Close every page's channel so open streams finish (server shutdown)."""
        for channel in list(self._watchers):
            channel.close()

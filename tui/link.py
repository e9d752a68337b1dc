"""The console's side of the bus: what it follows, what it asks, and how it sends commands.

Follows ``fleet``, ``jobs/*``, ``events``, ``vehicles/*/telemetry``, ``vehicles/*/status`` and the
liveliness of the vehicles and of the orchestrator; asks the orchestrator's ``snapshot`` queryable
(late joiner) and sends :class:`OperatorCommand` to its ``command`` queryable. Callbacks run on
Zenoh's threads and only decode and hand items to ``deliver``; they never touch widgets.

Zenoh itself is imported by :mod:`bus` only; this module uses the session it is given.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from typing import Any

import msgspec

from bus.codec import MessageError
from bus.keys import ShowKeys, vehicle_id_from_key
from bus.messages import (
    CommandReply,
    ErrorInfo,
    Event,
    JobState,
    OperatorCommand,
    ShowSnapshot,
    Telemetry,
    VehicleStatus,
)
from bus.pubsub import subscribe, watch_liveliness
from bus.rpc import NoReplyError, RemoteError, aquery_one
from bus.session import BusError, Session
from tui.inputs import BadPayload, BusInput, OrchestratorPresence, VehiclePresence

Deliver = Callable[[BusInput], None]


class LinkError(Exception):
    """Root of the console's bus errors."""


class ConsoleLink:
    """Subscriptions and queries of one console on one Zenoh session."""

    def __init__(self, session: Session, keys: ShowKeys) -> None:
        self._session = session
        self.keys = keys
        """Key expressions of the show."""
        self._declared: list[Any] = []
        self._deliver: Deliver | None = None

    def start(self, deliver: Deliver) -> None:
        """Declare the subscriptions; ``deliver`` is then called from Zenoh's threads."""
        if self._declared:
            raise LinkError("link already started")
        self._deliver = deliver
        k = self.keys
        typed: list[tuple[str, type[msgspec.Struct]]] = [
            (k.fleet, ShowSnapshot),
            (k.jobs_all, JobState),
            (k.events, Event),
            (k.telemetry_all, Telemetry),
            (k.vehicle_status_all, VehicleStatus),
        ]
        for key, message_type in typed:
            self._declared.append(
                subscribe(self._session, key, message_type, self._on_message, on_error=self._on_bad)
            )
        self._declared.append(
            watch_liveliness(self._session, k.vehicles_alive_all, self._on_vehicle_alive)
        )
        self._declared.append(
            watch_liveliness(self._session, k.orchestrator_alive, self._on_orchestrator_alive)
        )

    def _on_message(self, key: str, message: Any) -> None:
        deliver = self._deliver
        if deliver is not None:
            deliver(message)

    def _on_bad(self, key: str, error: MessageError) -> None:
        deliver = self._deliver
        if deliver is not None:
            deliver(BadPayload(key, error.info.message))

    def _on_vehicle_alive(self, key: str, alive: bool) -> None:
        deliver = self._deliver
        if deliver is None:
            return
        try:
            vehicle_id = vehicle_id_from_key(key)
        except ValueError:
            return
        deliver(VehiclePresence(vehicle_id, alive=alive))

    def _on_orchestrator_alive(self, key: str, alive: bool) -> None:
        deliver = self._deliver
        if deliver is not None:
            deliver(OrchestratorPresence(alive=alive))

    async def query_snapshot(self, timeout_s: float = 2.0) -> ShowSnapshot | None:
        """Ask the orchestrator for the whole show; None when nobody answers."""
        try:
            return await aquery_one(
                self._session, self.keys.snapshot, None, ShowSnapshot, timeout_s=timeout_s
            )
        except (BusError, MessageError):
            return None

    async def send_command(self, command: OperatorCommand, timeout_s: float = 3.0) -> CommandReply:
        """Send an operator command and wait for the answer (never raises)."""
        try:
            return await aquery_one(
                self._session, self.keys.command, command, CommandReply, timeout_s=timeout_s
            )
        except NoReplyError:
            info = ErrorInfo(code="no_answer", message="no answer from the orchestrator")
        except RemoteError as exc:
            info = exc.info
        except Exception as exc:  # a closed session or a Zenoh error must not kill the console
            info = ErrorInfo(code="bus_error", message=f"{type(exc).__name__}: {exc}")
        return CommandReply(ok=False, error=info)

    def close(self) -> None:
        """Undeclare everything (before the session closes)."""
        self._deliver = None
        for entity in reversed(self._declared):
            with contextlib.suppress(Exception):  # already gone with the session
                entity.undeclare()
        self._declared.clear()

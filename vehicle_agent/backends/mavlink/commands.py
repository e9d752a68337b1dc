"""COMMAND_LONG with retries, answered by COMMAND_ACK, explained by the autopilot's STATUSTEXT.

A refused command raises :class:`CommandRejectedError` (:class:`ArmingRefusedError` for arming)
whose ``reason`` is what the autopilot said between our request and its answer (ArduPilot sends
"PreArm: ..." just before the ACK); a command never answered raises
:class:`CommandTimeoutError` after ``attempts`` tries (the ``confirmation`` field counts them).
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Callable
from typing import Any

from vehicle_agent.backends.mavlink.errors import (
    ArmingRefusedError,
    CommandRejectedError,
    CommandTimeoutError,
)
from vehicle_agent.backends.mavlink.link import MavlinkLink
from vehicle_agent.backends.mavlink.state import LinkState

RESULT_ACCEPTED, RESULT_IN_PROGRESS = 0, 5
REASON_GRACE_S = 0.05
"""After a refusal, how long to wait for a STATUSTEXT sent just after the ACK, in [s]."""


class CommandChannel:
    """Commands to the autopilot of ``state`` over the link ``link()`` returns."""

    def __init__(
        self, link: Callable[[], MavlinkLink], state: LinkState, *, timeout_s: float, attempts: int
    ) -> None:
        self._link = link
        self._state = state
        self.timeout_s = timeout_s
        self.attempts = attempts
        self._waiters: list[tuple[int, asyncio.Future[int]]] = []
        self._texts: list[str] = []

    def send(self, command: int, *params: float, confirmation: int = 0) -> None:
        """Send one COMMAND_LONG without waiting (params padded to seven)."""
        padded = [*params, *([0.0] * (7 - len(params)))]
        st, link = self._state, self._link()
        link.send(link.mav.command_long_encode(
            st.system_id or 0, st.component_id or 0, command, confirmation, *padded))  # fmt: skip

    async def run(self, command: int, *params: float, arming: bool = False) -> None:
        """Send until acknowledged; raise if refused or never answered."""
        loop = asyncio.get_running_loop()
        for attempt in range(self.attempts):
            future: asyncio.Future[int] = loop.create_future()
            entry = (command, future)
            self._waiters.append(entry)
            texts_before = len(self._texts)
            self.send(command, *params, confirmation=attempt)
            try:
                result = await asyncio.wait_for(future, self.timeout_s)
            except TimeoutError:
                continue
            finally:
                with contextlib.suppress(ValueError):
                    self._waiters.remove(entry)
            if result == RESULT_ACCEPTED:
                return
            await asyncio.sleep(REASON_GRACE_S)
            reason = "; ".join(self._texts[texts_before:]) or None
            raise (ArmingRefusedError if arming else CommandRejectedError)(command, result, reason)
        raise CommandTimeoutError(
            f"no COMMAND_ACK for command {command} after {self.attempts} tries"
        )

    def on_ack(self, message: Any) -> None:
        """A COMMAND_ACK for us: the oldest request of that command gets its result."""
        result = int(message.result)
        if result == RESULT_IN_PROGRESS:
            return
        for waiting_for, future in self._waiters:
            if waiting_for == int(message.command) and not future.done():
                future.set_result(result)
                return

    def on_text(self, text: str) -> None:
        """A STATUSTEXT of the autopilot (kept briefly as a possible refusal reason)."""
        self._texts.append(text)
        if len(self._texts) > 64:
            del self._texts[:32]

    def cancel_all(self) -> None:
        for _, future in self._waiters:
            future.cancel()
        self._waiters.clear()

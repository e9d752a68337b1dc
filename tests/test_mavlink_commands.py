"""COMMAND_LONG retries and refusal reasons, against a scripted autopilot (no sockets)."""

from __future__ import annotations

import asyncio
from types import SimpleNamespace
from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from vehicle_agent.backends.mavlink.commands import CommandChannel
from vehicle_agent.backends.mavlink.errors import (
    ArmingRefusedError,
    CommandRejectedError,
    CommandTimeoutError,
)
from vehicle_agent.backends.mavlink.state import LinkState


class ScriptedLink:
    """Records COMMAND_LONGs; ``answer(n, message)`` says how the autopilot reacts to the n-th."""

    def __init__(self, channel_answer: Any) -> None:
        self.mav = mavlink.MAVLink(None, srcSystem=255, srcComponent=191)
        self.sent: list[Any] = []
        self.answer = channel_answer

    def send(self, message: Any) -> bool:
        self.sent.append(message)
        asyncio.get_running_loop().call_soon(self.answer, len(self.sent), message)
        return True


def channel(answer: Any, attempts: int = 3) -> tuple[CommandChannel, ScriptedLink]:
    link = ScriptedLink(answer)
    state = LinkState(7)
    return CommandChannel(lambda: link, state, timeout_s=0.05, attempts=attempts), link  # type: ignore[arg-type,return-value]


def ack(command: int, result: int) -> Any:
    return SimpleNamespace(command=command, result=result)


def test_a_lost_request_is_sent_again_and_a_late_ack_does_not_confuse_the_retry() -> None:
    async def scenario() -> None:
        def answer(n: int, message: Any) -> None:
            if n == 2:  # the first request was lost; its late ACK and the retry's both arrive
                commands.on_ack(ack(message.command, 0))

        commands, link = channel(answer)
        await commands.run(mavlink.MAV_CMD_DO_SET_MODE, 1, 4)
        assert [m.confirmation for m in link.sent] == [0, 1]
        assert (link.sent[0].target_system, link.sent[0].param2) == (7, 4.0)

    asyncio.run(scenario())


def test_a_refusal_carries_the_text_the_autopilot_sent_with_it() -> None:
    async def scenario() -> None:
        def answer(_n: int, message: Any) -> None:
            commands.on_text("PreArm: Need Position Estimate")
            commands.on_ack(ack(message.command, mavlink.MAV_RESULT_FAILED))

        commands, _ = channel(answer)
        with pytest.raises(ArmingRefusedError) as refused:
            await commands.run(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1, arming=True)
        assert refused.value.reason == "PreArm: Need Position Estimate"
        assert str(refused.value) == (
            "autopilot refused COMPONENT_ARM_DISARM (FAILED): PreArm: Need Position Estimate"
        )

    asyncio.run(scenario())


def test_in_progress_waits_for_the_final_answer_and_silence_times_out() -> None:
    async def scenario() -> None:
        def answer(_n: int, message: Any) -> None:
            commands.on_ack(ack(message.command, mavlink.MAV_RESULT_IN_PROGRESS))
            commands.on_ack(ack(message.command, mavlink.MAV_RESULT_DENIED))

        commands, _ = channel(answer)
        with pytest.raises(CommandRejectedError, match="DENIED") as refused:
            await commands.run(mavlink.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, 1.0)
        assert refused.value.reason is None and not isinstance(refused.value, ArmingRefusedError)

        silent, link = channel(lambda _n, _m: None, attempts=2)
        with pytest.raises(CommandTimeoutError, match="after 2 tries"):
            await silent.run(mavlink.MAV_CMD_NAV_LAND)
        assert len(link.sent) == 2

    asyncio.run(scenario())

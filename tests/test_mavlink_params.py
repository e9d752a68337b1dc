"""Setting a show's parameters over real MAVLink bytes: a stale PARAM_VALUE that overtakes the
answer (a parameter list being streamed; PX4 SITL under load read MPC_XY_VEL_I_ACC back as its
old 0.4 once, and refused the vehicle for good) costs one more set, not the vehicle; a value
the autopilot will not hold still refuses it, with what was read and how often it was set."""

from __future__ import annotations

import asyncio
from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from vehicle_agent.backends.mavlink.params import (
    MAV_PARAM_TYPE_REAL32,
    ParamChannel,
    ParamError,
    ParamSpec,
)
from vehicle_agent.backends.mavlink.state import LinkState

SPEC = ParamSpec("MPC_XY_VEL_I_ACC", 1.6, MAV_PARAM_TYPE_REAL32, why="velocity loop I")
OLD_VALUE = 0.4
"""PX4's default for the parameter."""


class Autopilot:
    """Parses the agent's bytes and answers as PX4 does (PARAM_VALUE for a set and for a read).
    ``stale_reads``: that many reads are answered first by a PARAM_VALUE carrying the value from
    before any set; ``holds``: whether a set value is kept (else it stays old)."""

    def __init__(self, channel: ParamChannel, *, stale_reads: int = 0, holds: bool = True) -> None:
        self.channel = channel
        self.stale_reads, self.holds = stale_reads, holds
        self.value, self.sets = OLD_VALUE, 0
        self.mav = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
        self._parser = mavlink.MAVLink(None)

    def receive(self, data: bytes) -> None:
        for message in self._parser.parse_buffer(data) or []:
            name = message.param_id.rstrip("\x00")
            if message.get_type() == "PARAM_SET":
                self.sets += 1
                if self.holds:
                    self.value = message.param_value
                self._answer(name, self.value)
            elif message.get_type() == "PARAM_REQUEST_READ":
                if self.stale_reads:
                    self.stale_reads -= 1
                    self._answer(name, OLD_VALUE)  # streamed before the set, overtakes the answer
                self._answer(name, self.value)

    def _answer(self, name: str, value: float) -> None:
        packed = self.mav.param_value_encode(name.encode(), value, MAV_PARAM_TYPE_REAL32, 1, 0)
        (decoded,) = self._parser.parse_buffer(packed.pack(self.mav))
        asyncio.get_running_loop().call_soon(self.channel.on_param_value, decoded)


class Link:
    """The agent's side: encodes as :class:`MavlinkLink` does and hands the bytes over."""

    def __init__(self) -> None:
        self.mav = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)
        self.autopilot: Autopilot | None = None

    def send(self, message: Any) -> bool:
        assert self.autopilot is not None
        self.autopilot.receive(message.pack(self.mav))
        return True


def _ensure(spec: ParamSpec = SPEC, **autopilot: Any) -> tuple[float | str, int]:
    """What ``ensure`` returns (or its error's text) and how many sets the autopilot saw."""

    async def scenario() -> tuple[float | str, int]:
        link = Link()
        channel = ParamChannel(
            lambda: link,  # type: ignore[arg-type,return-value]
            LinkState(1),
            lambda: "px4",
            timeout_s=0.5,
            attempts=3,
        )
        link.autopilot = ap = Autopilot(channel, **autopilot)
        try:
            return await channel.ensure(spec), ap.sets
        except ParamError as exc:
            return str(exc), ap.sets

    return asyncio.run(scenario())


def test_a_set_read_back_right_away_holds_with_one_set() -> None:
    assert _ensure() == (pytest.approx(1.6), 1)


@pytest.mark.parametrize("stale_reads", [1, 2])
def test_a_stale_value_read_back_is_set_again_not_a_refused_vehicle(stale_reads: int) -> None:
    value, sets = _ensure(stale_reads=stale_reads)
    assert value == pytest.approx(1.6) and sets == stale_reads + 1


def test_a_value_the_autopilot_does_not_hold_refuses_the_vehicle_saying_what_it_read() -> None:
    said, sets = _ensure(holds=False)
    assert sets == 3
    assert said == (
        "parameter MPC_XY_VEL_I_ACC (velocity loop I) is 0.4 after setting it to 1.6 3 times"
    )


@pytest.mark.parametrize(("at_most", "value", "sets"), [(1.6, OLD_VALUE, 0), (0.4, OLD_VALUE, 0),
                                                         (0.1, 0.1, 1)])  # fmt: skip
def test_a_ceiling_keeps_a_smaller_value_the_airframe_has_and_lowers_a_larger_one(
    at_most: float, value: float, sets: int
) -> None:
    """EKF2_TAU_VEL: the show needs the velocity within 0.1 s of the mocap's; an airframe tuned
    to 0.03 keeps it (the parameter stands at 0.4 here, below a ceiling of 1.6 or at 0.4)."""
    spec = ParamSpec("MPC_XY_VEL_I_ACC", at_most, MAV_PARAM_TYPE_REAL32, at_most=True)
    assert _ensure(spec) == (pytest.approx(value), sets)

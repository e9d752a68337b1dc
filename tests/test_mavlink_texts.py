"""STATUSTEXTs sent in chunks (PX4, texts over 50 characters) are handed on as one text, on real
MAVLink 2 bytes: a whole text (id 0), a text in two chunks, a chunk sequence cut short."""

from __future__ import annotations

from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from vehicle_agent.backends.mavlink.state import (
    MAV_SYS_STATUS_PREARM_CHECK,
    PREARM_UNSAID,
    PX4,
    PX4_OFFBOARD_ON_GROUND,
    STATUSTEXT_CHARS,
    STATUSTEXT_JOIN_WAIT_S,
    LinkState,
)

AUTOPILOT_ID = 7
PX4_DENIAL = "Arming denied: Resolve system health failures first"
"""51 characters: PX4 sends "...health failures firs" and "t"."""
WARNING = mavlink.MAV_SEVERITY_WARNING


def wire(message: Any) -> Any:
    """``message`` as the agent receives it: packed by the autopilot, parsed back."""
    sender = mavlink.MAVLink(None, srcSystem=AUTOPILOT_ID, srcComponent=1)
    (decoded,) = mavlink.MAVLink(None).parse_buffer(message.pack(sender))
    return decoded


def chunks(text: str, text_id: int, severity: int = WARNING) -> list[Any]:
    """``text`` as PX4's STATUSTEXT stream sends it: 50 characters per chunk, one ``id``."""
    pieces = [text[i : i + STATUSTEXT_CHARS] for i in range(0, len(text), STATUSTEXT_CHARS)]
    return [
        wire(mavlink.MAVLink_statustext_message(severity, piece.encode(), text_id, seq))
        for seq, piece in enumerate(pieces)
    ]


class Clock:
    def __init__(self) -> None:
        self.now_s = 100.0

    def __call__(self) -> float:
        return self.now_s


def connected(autopilot: int) -> tuple[LinkState, Clock]:
    clock = Clock()
    state = LinkState(clock=clock)
    heartbeat = mavlink.MAVLink_heartbeat_message(mavlink.MAV_TYPE_QUADROTOR, autopilot, 0, 0, 3, 3)
    assert state.absorb(wire(heartbeat)) == "HEARTBEAT"
    return state, clock


def test_a_text_of_one_chunk_is_handed_on_at_once() -> None:
    state, _ = connected(mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA)
    (message,) = chunks("PreArm: Need Position Estimate", 0, mavlink.MAV_SEVERITY_CRITICAL)
    assert message.id == 0 and message.chunk_seq == 0
    assert state.absorb(message) == "STATUSTEXT"
    assert state.recent_texts[-1] == (
        mavlink.MAV_SEVERITY_CRITICAL,
        "PreArm: Need Position Estimate",
    )
    assert state.take_texts() == [(mavlink.MAV_SEVERITY_CRITICAL, "PreArm: Need Position Estimate")]


def test_a_text_in_two_chunks_is_handed_on_once_whole() -> None:
    state, _ = connected(mavlink.MAV_AUTOPILOT_PX4)
    first, last = chunks(PX4_DENIAL, 41)
    assert (first.text, last.text, last.chunk_seq) == (PX4_DENIAL[:50], "t", 1)
    assert state.absorb(first) == ""  # waits for the rest: nothing to hand on yet
    assert state.take_texts() == []
    assert state.absorb(last) == "STATUSTEXT"
    assert state.recent_texts[-1] == (WARNING, PX4_DENIAL)
    assert state.take_texts() == [(WARNING, PX4_DENIAL)]


def test_px4s_first_text_of_a_link_joins_although_its_id_is_0() -> None:
    """PX4 numbers texts per link from 0: its first one, if chunked, has id 0 (the one that was
    seen split as "...health failures firs" and "t")."""
    state, _ = connected(mavlink.MAV_AUTOPILOT_PX4)
    first, last = chunks(PX4_DENIAL, 0)
    assert [state.absorb(first), state.absorb(last)] == ["", "STATUSTEXT"]
    assert state.take_texts() == [(WARNING, PX4_DENIAL)]


def test_a_full_text_of_id_0_is_whole_from_ardupilot_and_waits_its_time_from_px4() -> None:
    """ArduPilot numbers chunked texts from 1: its id 0 of exactly 50 characters is one text,
    handed on at once (an arming refusal's reason is heard in time). From PX4 it may go on."""
    full = "z" * STATUSTEXT_CHARS
    ardupilot, _ = connected(mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA)
    (message,) = chunks(full, 0)
    assert ardupilot.absorb(message) == "STATUSTEXT"
    assert ardupilot.take_texts() == [(WARNING, full)]
    px4, clock = connected(mavlink.MAV_AUTOPILOT_PX4)
    assert px4.absorb(message) == ""
    clock.now_s += STATUSTEXT_JOIN_WAIT_S
    assert px4.take_texts() == [(WARNING, full)]


def test_a_cut_sequence_is_handed_on_as_far_as_it_came_when_the_next_text_begins() -> None:
    state, _ = connected(mavlink.MAV_AUTOPILOT_PX4)
    long_text = "x" * STATUSTEXT_CHARS + "y" * STATUSTEXT_CHARS + "z"
    first, _lost, last = chunks(long_text, 9)
    (next_text,) = chunks("Takeoff detected", 10, mavlink.MAV_SEVERITY_INFO)
    assert state.absorb(first) == ""
    assert state.absorb(last) == "STATUSTEXT"  # chunk 1 never came: 0 and 2 are not one text
    assert state.take_texts() == [(WARNING, "x" * STATUSTEXT_CHARS), (WARNING, "z")]
    assert state.absorb(first) == ""
    assert state.absorb(next_text) == "STATUSTEXT"
    assert list(state.recent_texts)[-2:] == [
        (WARNING, "x" * STATUSTEXT_CHARS),
        (mavlink.MAV_SEVERITY_INFO, "Takeoff detected"),
    ]


def test_a_part_waits_for_its_next_chunk_only_so_long() -> None:
    """A text of exactly 100 characters: PX4 sends two full chunks and no short one."""
    state, clock = connected(mavlink.MAV_AUTOPILOT_PX4)
    text = "Preflight Fail: " + "a" * (2 * STATUSTEXT_CHARS - 16)
    first, second = chunks(text, 12)
    assert [state.absorb(first), state.absorb(second)] == ["", ""]
    clock.now_s += STATUSTEXT_JOIN_WAIT_S * 0.9
    assert state.take_texts() == []
    clock.now_s += STATUSTEXT_JOIN_WAIT_S * 0.1
    assert state.take_texts() == [(WARNING, text)]
    assert state.recent_texts[-1] == (WARNING, text) and state.take_texts() == []
    assert state.take_to_tell() == [(WARNING, text)]  # the event log hears it too, once


def test_the_event_log_hears_both_texts_one_chunk_completes() -> None:
    state, _ = connected(mavlink.MAV_AUTOPILOT_PX4)
    first, _lost, _last = chunks("x" * STATUSTEXT_CHARS * 2 + "z", 9)
    (next_text,) = chunks("Takeoff detected", 10, mavlink.MAV_SEVERITY_INFO)
    state.absorb(first)
    state.absorb(next_text)
    assert state.take_to_tell() == [
        (WARNING, "x" * STATUSTEXT_CHARS),
        (mavlink.MAV_SEVERITY_INFO, "Takeoff detected"),
    ]
    assert state.take_to_tell() == [] and len(state.take_texts()) == 2  # the watchdog's own


def test_texts_of_another_system_are_not_joined_into_ours() -> None:
    state, _ = connected(mavlink.MAV_AUTOPILOT_PX4)
    first, last = chunks(PX4_DENIAL, 3)
    sender = mavlink.MAVLink(None, srcSystem=AUTOPILOT_ID + 1, srcComponent=1)
    (other,) = mavlink.MAVLink(None).parse_buffer(
        mavlink.MAVLink_statustext_message(WARNING, b"not ours", 0, 0).pack(sender)
    )
    assert [state.absorb(first), state.absorb(other), state.absorb(last)] == ["", "", "STATUSTEXT"]
    assert state.take_texts() == [(WARNING, PX4_DENIAL)]


@pytest.mark.parametrize("text_id", [0, 77])
@pytest.mark.parametrize("length", [1, 49, 50, 51, 99, 100, 101, 149, 250])
def test_every_length_comes_back_whole(length: int, text_id: int) -> None:
    state, clock = connected(mavlink.MAV_AUTOPILOT_PX4)
    text = "".join(chr(ord("a") + i % 26) for i in range(length))
    for message in chunks(text, text_id):
        state.absorb(message)
    clock.now_s += STATUSTEXT_JOIN_WAIT_S  # a full last chunk is handed on after the wait
    assert state.take_texts() == [(WARNING, text)]


def test_px4s_event_tab_never_reaches_the_operator() -> None:
    """PX4 ends a text it also sends as an event with a tab; the refusal the operator reads
    ended with it ("...health failures first\t")."""
    state, _ = connected(mavlink.MAV_AUTOPILOT_PX4)
    for message in chunks("Arming denied: Resolve system health failures first\t", 7):
        state.absorb(message)
    assert state.take_texts() == [(WARNING, "Arming denied: Resolve system health failures first")]


def sys_status(prearm_good: bool) -> Any:
    """SYS_STATUS as PX4 sends it: the pre-arm bit in health only."""
    health = MAV_SYS_STATUS_PREARM_CHECK if prearm_good else 0
    return wire(mavlink.MAVLink_sys_status_message(0, 0, health, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0))


def test_the_pre_arm_explanation_is_the_autopilots_latest_while_the_checks_fail() -> None:
    state, _ = connected(mavlink.MAV_AUTOPILOT_PX4)
    assert state.preflight is None  # no SYS_STATUS yet
    state.absorb(sys_status(prearm_good=False))
    assert state.preflight == PREARM_UNSAID  # failing, not said why (yet)
    (vertical,) = chunks("Preflight Fail: vertical velocity unstable\t", 3)  # PX4's tab
    state.absorb(vertical)
    assert state.preflight == "Preflight Fail: vertical velocity unstable"
    for message in chunks(PX4_DENIAL, 4):  # a refused ARM names no check: not better
        state.absorb(message)
    state.absorb(sys_status(prearm_good=False))
    assert state.preflight == "Preflight Fail: vertical velocity unstable"
    (horizontal,) = chunks("Preflight Fail: horizontal velocity unstable", 5)
    state.absorb(horizontal)
    assert state.preflight == "Preflight Fail: horizontal velocity unstable"
    state.absorb(sys_status(prearm_good=True))
    assert (state.preflight, state.prearm_text) == (None, None)  # forgotten once they pass
    for message in chunks(PX4_DENIAL, 6):  # the only words of the next failure
        state.absorb(message)
    state.absorb(sys_status(prearm_good=False))
    assert state.preflight == PX4_DENIAL


def test_px4_in_offboard_on_the_ground_is_not_judged_by_its_pre_arm_bit() -> None:
    """PX4 sets the bit for the mode it is in; back in OFFBOARD after a landing, with no
    setpoints streaming, it stays clear whatever the checks say: not ready, but not for a
    failing check (the agent puts it in Hold). In Hold the bit counts, and armed in OFFBOARD
    (flying) the vehicle is not on the ground."""
    state, _ = connected(mavlink.MAV_AUTOPILOT_PX4)
    hold = PX4.ground_mode
    assert hold is not None
    cases = [(PX4.offboard_mode, False, False, PX4_OFFBOARD_ON_GROUND),
             (PX4.offboard_mode, True, False, PX4_OFFBOARD_ON_GROUND),
             (hold, False, False, PREARM_UNSAID), (hold, True, False, None),
             (PX4.offboard_mode, True, True, None)]  # fmt: skip
    for mode, good, armed, wanted in cases:
        flags = mavlink.MAV_MODE_FLAG_SAFETY_ARMED if armed else 0
        beat = mavlink.MAVLink_heartbeat_message(
            mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_PX4, 1 | flags, mode, 3, 3
        )
        state.absorb(wire(beat))
        state.absorb(sys_status(prearm_good=good))
        assert state.preflight == wanted, (mode, good, armed)


def test_ardupilot_in_guided_on_the_ground_is_judged_by_its_bit() -> None:
    state, _ = connected(mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA)
    beat = mavlink.MAVLink_heartbeat_message(
        mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, 1, 4, 3, 3
    )
    state.absorb(wire(beat))
    state.absorb(sys_status(prearm_good=True))
    assert state.in_offboard_on_ground and state.preflight is None

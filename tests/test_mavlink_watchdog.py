"""The watchdog's verdict on mode changes (pure): a mode change we did not command is a fault
once two heartbeats in a row say it; one stale heartbeat (said before our command took effect,
or PX4's mode-to-come one heartbeat before its disarm after a landing) is not."""

from __future__ import annotations

from vehicle_agent.backends.mavlink.state import PX4, LinkState
from vehicle_agent.backends.mavlink.watchdog import Commanded, Watchdog, WatchLimits

LIMITS = WatchLimits(
    heartbeat_timeout_s=3.0, setpoint_timeout_s=1.0, takeoff_timeout_s=30.0, land_timeout_s=30.0
)
OFFBOARD, LAND = PX4.offboard_mode, PX4.land_mode


def heartbeat(state: LinkState, custom_mode: int, armed: bool) -> None:
    state.heartbeats += 1
    state.custom_mode, state.armed = custom_mode, armed


def verdicts(
    beats: list[tuple[int, bool]], mode: str, commanded_mode: int, landed_state: int | None = None
) -> list[str | None]:
    """The watchdog's verdict after each heartbeat (one tick each, 1 s apart, setpoints fresh)."""
    state, dog = LinkState(1), Watchdog(LIMITS)
    state.landed_state = landed_state
    commanded = Commanded(commanded_mode, at_heartbeat=0, last_sent_s=0.0)
    out = []
    for k, (custom_mode, armed) in enumerate(beats):
        heartbeat(state, custom_mode, armed)
        now_s = float(k)
        commanded = Commanded(commanded_mode, at_heartbeat=0, last_sent_s=now_s)
        out.append(dog.check(now_s, 0.01, state, PX4, mode, commanded))  # type: ignore[arg-type]
    return out


def test_one_stale_heartbeat_after_landing_is_no_fault() -> None:
    """PX4 after a commanded landing: LAND, then OFFBOARD still armed (the mode it goes back
    to), then OFFBOARD disarmed: the landing is over, no fault."""
    beats = [(LAND, True), (OFFBOARD, True), (OFFBOARD, False), (OFFBOARD, False)]
    assert verdicts(beats, "landing", LAND) == [None, None, None, None]


def test_a_mode_change_said_twice_is_a_fault() -> None:
    beats = [(OFFBOARD, True), (LAND, True), (LAND, True)]
    found = verdicts(beats, "offboard", OFFBOARD)
    assert found[:2] == [None, None]
    assert found[2] is not None and "mode changed to" in found[2]


def test_a_mode_said_once_between_ours_is_forgotten() -> None:
    beats = [(OFFBOARD, True), (LAND, True), (OFFBOARD, True), (LAND, True), (OFFBOARD, True)]
    assert verdicts(beats, "offboard", OFFBOARD) == [None] * 5


def test_a_disarm_says_whether_the_vehicle_had_left_the_ground() -> None:
    """PX4 disarms a vehicle that did not climb within its preflight timeout: on the ground, the
    fault says so instead of a disarm in flight (PX4 SIH at load 6, issue 31)."""
    beats = [(OFFBOARD, True), (OFFBOARD, False)]
    on_ground = verdicts(beats, "takeoff", OFFBOARD, landed_state=1)
    in_air = verdicts(beats, "takeoff", OFFBOARD, landed_state=2)
    assert on_ground[0] is None and "on the ground before it climbed" in str(on_ground[1])
    assert in_air[0] is None and "disarmed in flight" in str(in_air[1])

"""What an autopilot does on MAVLink, as a companion computer relies on it: one suite, run against
mavsim (ArduPilot and PX4 flavours) and, when configured, against ArduCopter and PX4 SITL.

The tests speak MAVLink bytes through pymavlink only (``mavlink_gcs.Gcs``), never through the
project's agent: they describe the autopilot. Where ArduPilot and PX4 differ, the test says which
answer it expects of which.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

import pytest
from mavlink_gcs import Gcs
from pymavlink.dialects.v20 import ardupilotmega as mav

pytestmark = pytest.mark.timeout(180)

HOLD_M = 0.6
"""How far a hovering vehicle may wander in [m]: PX4 SITL on simulated GPS drifts ~0.3-0.5 m;
the tests tell behaviours apart with moves of 1.5 m."""
MOVE_M = 1.5

ACCEPTED = mav.MAV_RESULT_ACCEPTED
AUTOPILOT_TYPES = {"ardupilot": mav.MAV_AUTOPILOT_ARDUPILOTMEGA, "px4": mav.MAV_AUTOPILOT_PX4}
TIMEOUT_PARAM = {"ardupilot": "GUID_TIMEOUT", "px4": "COM_OF_LOSS_T"}


@pytest.fixture
def gcs(autopilot: Any) -> Iterator[Gcs]:
    link = Gcs(autopilot.url, autopilot.system_id, autopilot.kind)
    try:
        link.connect()
        yield link
    finally:
        link.close()


def test_heartbeat_names_the_autopilot_and_it_rests_disarmed(gcs: Gcs) -> None:
    hb = gcs.seen.heartbeat
    assert hb.autopilot == AUTOPILOT_TYPES[gcs.kind]
    assert hb.type == mav.MAV_TYPE_QUADROTOR and not gcs.armed


def test_a_mode_change_is_acknowledged_and_shown_in_the_heartbeat(gcs: Gcs) -> None:
    assert gcs.set_mode("LOITER") == ACCEPTED
    assert gcs.pump(3.0, lambda _s: gcs.in_mode("LOITER"))


def test_arming_in_land_is_refused_with_a_reason_to_a_ground_station(gcs: Gcs) -> None:
    assert gcs.set_mode("LAND") == ACCEPTED
    gcs.seen.texts.clear()
    assert gcs.arm() != ACCEPTED
    assert gcs.pump(1.0, lambda s: bool(s.texts)), "no STATUSTEXT explains the refusal"
    gcs.pump(1.0)
    assert not gcs.armed


@pytest.mark.parametrize(
    ("mav_type", "px4_texts"),
    [(mav.MAV_TYPE_GCS, True), (mav.MAV_TYPE_ONBOARD_CONTROLLER, False)],
)
def test_px4_sends_statustext_only_to_links_with_a_ground_station(
    autopilot: Any, mav_type: int, px4_texts: bool
) -> None:
    link = Gcs(autopilot.url, autopilot.system_id, autopilot.kind, mav_type=mav_type)
    try:
        link.connect()
        link.pump(3.0)  # a ground station heard before (a readiness probe) is forgotten in 2.5 s
        assert link.set_mode("LAND") == ACCEPTED
        assert link.arm() != ACCEPTED
        link.pump(2.0)
        expected = px4_texts or autopilot.kind == "ardupilot"  # ArduPilot tells every link
        assert bool(link.seen.texts) == expected, link.seen.texts
    finally:
        link.close()


def test_parameters_are_set_read_back_and_unknown_ones_unanswered(gcs: Gcs) -> None:
    name = TIMEOUT_PARAM[gcs.kind]
    assert gcs.set_param(name, 0.8, mav.MAV_PARAM_TYPE_REAL32) == pytest.approx(0.8)
    assert gcs.set_param("SKYQUILL_NO_SUCH", 1.0, mav.MAV_PARAM_TYPE_REAL32) is None


@pytest.mark.slow
def test_take_off_climbs_and_holds(gcs: Gcs) -> None:
    gcs.airborne(1.0)
    assert gcs.armed and gcs.in_mode("GUIDED")
    start = gcs.here()
    gcs.pump(2.0)
    assert math.dist(gcs.here(), start) < HOLD_M


MOVE_MASKS = [
    pytest.param(0x0C00, "position", id="0x0C00-pos-vel-acc"),
    pytest.param(0x0800, "position", id="0x0800-pos-vel-acc-yaw"),
    pytest.param(0x0DF8, "position", id="0x0DF8-pos"),
    pytest.param(0x09F8, "position", id="0x09F8-pos-yaw"),
    pytest.param(0x0FF8, "position", id="0x0FF8-pos-force-bit-acc-ignored"),
    pytest.param(0x0FC7, "velocity", id="0x0FC7-vel"),
]


@pytest.mark.slow
@pytest.mark.parametrize(("mask", "what"), MOVE_MASKS)
def test_setpoint_type_masks_that_move_the_vehicle(gcs: Gcs, mask: int, what: str) -> None:
    """Each mask moves the vehicle 1.5 m north (the force bit is harmless while acceleration is
    ignored: ArduCopter rejects it only together with an acceleration)."""
    gcs.airborne(1.0)
    x, y, z = gcs.here()
    yaw = gcs.yaw_rad()
    goal = (x + MOVE_M, y, z)
    if what == "position":
        gcs.stream = lambda g: g.send_target(mask, goal, yaw=yaw)
    else:
        gcs.stream = lambda g: g.send_target(mask, v=(0.5 if g.here()[0] < x + MOVE_M else 0.0,
                                                      0.0, 0.0))  # fmt: skip
    assert gcs.pump(12.0, lambda s: s.position.x > x + MOVE_M - HOLD_M / 2), f"{mask:#06x}"
    assert abs(gcs.here()[1] - y) < HOLD_M and abs(gcs.here()[2] - z) < HOLD_M


@pytest.mark.slow
def test_a_force_setpoint_with_acceleration_does_not_move_the_vehicle(gcs: Gcs) -> None:
    """Mask 0x0C00 | force: ArduCopter stops where it is, PX4 ignores it; neither flies there."""
    gcs.airborne(1.0)
    x, y, z = gcs.here()
    gcs.stream = lambda g: g.send_target(0x0E00, (x + MOVE_M, y, z))
    gcs.pump(4.0)
    assert gcs.here()[0] - x < MOVE_M - HOLD_M


@pytest.mark.slow
def test_yaw_is_held_when_given_and_turned_when_asked(gcs: Gcs) -> None:
    gcs.airborne(1.0)
    here, yaw = gcs.here(), gcs.yaw_rad()
    goal = (here[0] + 0.6, here[1] + 0.6, here[2])  # diagonal: a look-ahead yaw would turn
    gcs.stream = lambda g: g.send_target(0x09F8, goal, yaw=yaw)
    gcs.pump(5.0, lambda s: math.dist(g_xy(s), goal[:2]) < 0.05)
    assert abs(_angle(gcs.yaw_rad() - yaw)) < math.radians(3.0)
    turned = _angle(yaw + math.pi / 2)
    gcs.stream = lambda g: g.send_target(0x09F8, goal, yaw=turned)
    assert gcs.pump(6.0, lambda s: abs(_angle(float(s.attitude.yaw) - turned)) < 0.05)


@pytest.mark.slow
def test_a_stopped_velocity_stream_stops_the_vehicle_after_the_timeout(gcs: Gcs) -> None:
    """GUID_TIMEOUT (ArduPilot: velocity zeroed) / COM_OF_LOSS_T (PX4: offboard lost, Hold)."""
    assert gcs.set_param(TIMEOUT_PARAM[gcs.kind], 1.0, mav.MAV_PARAM_TYPE_REAL32) == 1.0
    gcs.airborne(1.0)
    x = gcs.here()[0]
    gcs.stream = lambda g: g.send_target(0x0FC7, v=(0.4, 0.0, 0.0))
    assert gcs.pump(4.0, lambda s: s.position.vx > 0.3)
    gcs.stream = None
    gcs.pump(4.0)
    assert gcs.speed_mps() < 0.3 and gcs.armed
    assert gcs.here()[0] - x < 0.4 * 4.0 + 0.4 * (1.0 + 1.5)


@pytest.mark.slow
def test_a_lost_link_leaves_the_vehicle_holding_and_it_answers_again(gcs: Gcs) -> None:
    gcs.airborne(1.0)
    gcs.stream = None
    where = gcs.here()
    gcs.silent = True
    gcs.pump(3.0)
    gcs.silent = False
    gcs.seen.position = None
    assert gcs.pump(12.0, lambda s: s.position is not None), "telemetry did not come back"
    assert gcs.armed and math.dist(gcs.here(), where) < HOLD_M
    assert gcs.set_mode("LAND") == ACCEPTED


@pytest.mark.slow
def test_land_descends_touches_down_and_disarms_by_itself(gcs: Gcs) -> None:
    gcs.airborne(1.0)
    gcs.stream = None
    assert gcs.set_mode("LAND") == ACCEPTED
    landed = gcs.pump(20.0, lambda s: not gcs.armed and s.extended is not None
                      and s.extended.landed_state == mav.MAV_LANDED_STATE_ON_GROUND)  # fmt: skip
    assert landed, f"still armed={gcs.armed} at {gcs.here()}"


def g_xy(seen: Any) -> tuple[float, float]:
    return (float(seen.position.x), float(seen.position.y))


def _angle(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi

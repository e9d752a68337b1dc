"""ESTIMATOR_STATUS as PX4 sends it (``mavsim/estimator.py``) and asked for by the agent at
connect (``vehicle_agent/backends/mavlink/connect.py``): EKF2's flags through boot, the ground
and the air; then over real MAVLink bytes, the agent's estimator check reading them."""

from __future__ import annotations

import asyncio

from pymavlink.dialects.v20 import ardupilotmega as mavlink
from test_mavlink_backend import airborne, connected, vehicle
from test_mavsim_px4 import HOME, Sim

from mavsim.config import VehicleConfig
from mavsim.endpoint import VehicleEndpoint
from mavsim.estimator import estimator_flags
from mavsim.px4 import Px4Autopilot
from mavsim.server import MavsimServer

BOOT = 1 | 4 | 32 | 128
"""Attitude, vertical velocity and position (the barometer), constant position (no source)."""
LOCAL = 2 | 8 | 256
"""Horizontal velocity, relative position, and horizontal aiding active."""


def test_ekf2s_flags_through_boot_the_ground_and_the_air_with_gnss() -> None:
    sim = Sim()
    sim.ap = Px4Autopilot(VehicleConfig(vehicle_id="v", system_id=1, port=0, home_m_enu=HOME,
                                        autopilot="px4", position_source_delay_s=2.0))  # fmt: skip
    assert estimator_flags(sim.ap) == BOOT | 512  # GNSS fused (EKF2_GPS_CTRL 7), not yet valid
    sim.run(2.5)
    on_ground = estimator_flags(sim.ap)
    assert on_ground == BOOT | LOCAL | 16 | 512  # at rest: CONST_POS_MODE stays, as in PX4 1.16
    sim.airborne()
    assert estimator_flags(sim.ap) == on_ground & ~128  # moving: no longer at rest


def test_with_mocap_alone_a_global_position_waits_for_the_origin() -> None:
    sim = Sim(EKF2_EV_CTRL=15, EKF2_GPS_CTRL=0, EKF2_HGT_REF=3)
    sim.ap.mocap_pose()
    sim.run(0.05)
    sim.ap.mocap_pose()
    assert estimator_flags(sim.ap) == BOOT | LOCAL
    sim.ap.ekf_origin_lla = (1.35, 103.98, 0.0)  # SET_GPS_GLOBAL_ORIGIN from the companion
    assert estimator_flags(sim.ap) == BOOT | LOCAL | 16
    sim.run(1.0)  # no pose for 1 s: EKF2 drops the vision (0.4 s), back to a fake position
    assert estimator_flags(sim.ap) == BOOT


def test_px4s_own_rate_is_half_a_hertz_and_ardupilot_sends_none() -> None:
    def endpoint(autopilot: str) -> VehicleEndpoint:
        config = VehicleConfig(vehicle_id="v", system_id=1, port=0, home_m_enu=HOME,
                               autopilot=autopilot)  # fmt: skip
        return VehicleEndpoint(config)

    px4, ardupilot = endpoint("px4"), endpoint("ardupilot")
    try:
        assert px4.intervals_s[mavlink.MAVLINK_MSG_ID_ESTIMATOR_STATUS] == 2.0
        assert mavlink.MAVLINK_MSG_ID_ESTIMATOR_STATUS not in ardupilot.intervals_s
        message = px4._telemetry(mavlink.MAVLINK_MSG_ID_ESTIMATOR_STATUS, 0.0)
        assert message is not None and message.get_type() == "ESTIMATOR_STATUS"
        assert message.pos_horiz_accuracy == 0.5 and message.pos_vert_accuracy == 3.5
    finally:
        px4.sock.close()
        ardupilot.sock.close()


def test_the_agent_asks_px4_for_it_and_its_check_reads_the_flags_over_mavlink() -> None:
    async def scenario(server: MavsimServer) -> None:
        async with connected(server) as (backend, driver):
            asked = server.endpoints[0].intervals_s[mavlink.MAVLINK_MSG_ID_ESTIMATOR_STATUS]
            snapshot = await driver.until(lambda s: s.health is not None, 1.0)
            while backend.state.estimator_flags is None:
                snapshot = await driver.tick()
            assert asked == 1.0  # 1 Hz, not PX4's 0.5 Hz of its own
            assert snapshot.health is not None
            early = snapshot.health.estimator
            snapshot = await driver.until(
                lambda s: s.health is not None and s.health.estimator is None, 8.0
            )
            assert early == "no horizontal velocity, no horizontal position"
            assert backend.state.estimator_flags == BOOT | LOCAL | 16 | 512
            # as the agent does, take off once the preflight says it can: SYS_STATUS's pre-arm
            # bit (1 Hz) may still say "Need Position Estimate" a moment after the estimator's
            # flags (1 Hz too) have cleared (it once did at load 4.8 in CI)
            await driver.until(lambda s: s.preflight is None, 3.0)
            await airborne(backend, driver)
            assert backend.state.estimator_flags is not None
            assert not backend.state.estimator_flags & 128

    with vehicle(autopilot="px4", position_source_delay_s=3.0) as server:
        asyncio.run(scenario(server))

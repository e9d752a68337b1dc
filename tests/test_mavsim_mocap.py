"""mavsim with motion capture as its only position source, as ArduCopter and PX4 behave on it:
no recent pose, no position (arming refused with the autopilot's own words); the read-at-boot
parameter counts only from boot; a show's mocap vehicle boots with it."""

from __future__ import annotations

import pytest

from mavsim.autopilot import Autopilot
from mavsim.autopilot_core import Result
from mavsim.config import VehicleConfig
from mavsim.px4 import Px4Autopilot
from mavsim.show import vehicle_configs
from showfile import parse_show

DT_S = 0.01


def ardupilot(**boot: float) -> Autopilot:
    config = VehicleConfig(vehicle_id="v", system_id=1, port=0, position_source_delay_s=0.0,
                           params=tuple(boot.items()))  # fmt: skip
    return Autopilot(config)


def px4(**boot: float) -> Px4Autopilot:
    config = VehicleConfig(vehicle_id="v", system_id=1, port=0, position_source_delay_s=0.0,
                           autopilot="px4", params=tuple(boot.items()))  # fmt: skip
    return Px4Autopilot(config)


def run(ap: Autopilot, seconds: float, *, poses_hz: float | None, t0: float = 0.0) -> float:
    """Step ``ap`` for ``seconds`` from ``t0``, a pose every 1/poses_hz s (None: none)."""
    t, next_pose = t0, t0
    for _ in range(round(seconds / DT_S)):
        t += DT_S
        ap.step(t)
        if poses_hz is not None and t >= next_pose:
            ap.mocap_pose()
            next_pose += 1.0 / poses_hz
    return t


def test_ardupilot_on_external_nav_arms_only_while_poses_arrive() -> None:
    ap = ardupilot(VISO_TYPE=1, EK3_SRC1_POSXY=6)
    t = run(ap, 1.0, poses_hz=None)
    assert ap.arm() == Result.FAILED
    assert ap.texts[-1][1] == "PreArm: VisOdom: not healthy"
    t = run(ap, 0.5, poses_hz=30.0, t0=t)
    assert ap.position_source_ready and ap.arm() == Result.ACCEPTED
    assert ap.disarm() == Result.ACCEPTED
    run(ap, 0.35, poses_hz=None, t0=t)  # AP_VISUALODOM_TIMEOUT_MS is 300
    assert not ap.position_source_ready and ap.arm() == Result.FAILED


def test_viso_type_counts_from_boot_only() -> None:
    ap = ardupilot(EK3_SRC1_POSXY=6)
    ap.params.set_from_link("VISO_TYPE", 1.0)  # stored, as ArduPilot does; read at the next boot
    run(ap, 1.0, poses_hz=None)
    assert ap.params["VISO_TYPE"] == 1.0 and not ap.fuses_mocap
    assert ap.arm() == Result.ACCEPTED


def test_px4_on_external_vision_only_arms_only_while_poses_arrive() -> None:
    ap = px4(EKF2_EV_CTRL=3, EKF2_GPS_CTRL=0)
    t = run(ap, 0.5, poses_hz=30.0)
    assert ap.position_source_ready
    run(ap, 0.45, poses_hz=None, t0=t)  # EKF2 stops the vision after 2 x EV_MAX_INTERVAL
    assert not ap.position_source_ready
    assert ap.arm() == Result.FAILED
    assert ap.texts[-1][1].startswith("Arming denied: Resolve system health failures")


@pytest.mark.parametrize(
    ("flavor", "params"),
    [("ardupilot", {"VISO_TYPE": 1}), ("px4", {"EKF2_EV_CTRL": 3})],  # no ExternalNav source;
)  # PX4 with its GPS still on
def test_without_mocap_as_the_position_source_poses_are_not_needed(
    flavor: str, params: dict[str, float]
) -> None:
    ap = ardupilot(**params) if flavor == "ardupilot" else px4(**params)
    run(ap, 1.0, poses_hz=None)
    assert not ap.fuses_mocap and ap.position_source_ready


def test_a_shows_mocap_vehicle_boots_with_what_fusing_it_needs() -> None:
    show = parse_show("""
show_id: m
boards:
  - {id: b1, center_m_enu: [0.0, 0.0, 0.75], size_m: [1.4, 1.4], writing_area_m: [0.6, 0.6]}
vehicles:
  - {id: v1, board: b1, home_m_enu: [0.0, -1.0, 0.0], backend: mavlink,
     mavlink_url: "udp:127.0.0.1:14601", mavlink_mocap: vision_position_estimate}
  - {id: v2, board: b1, home_m_enu: [1.0, -1.0, 0.0], backend: mavlink,
     mavlink_url: "udp:127.0.0.1:14602"}
""")
    ardu = {c.vehicle_id: dict(c.params) for c in vehicle_configs(show)}
    assert ardu == {"v1": {"VISO_TYPE": 1}, "v2": {}}
    (v1, _) = vehicle_configs(show, autopilot="px4")
    assert dict(v1.params) == {"EKF2_ASP_DELAY": 0.0, "EKF2_DELAY_MAX": 20.0}

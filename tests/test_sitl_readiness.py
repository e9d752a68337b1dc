"""scripts/sitl/readiness.py: when start.py calls a fresh SITL instance ready, fed the messages
an autopilot sends on start.py's own link (the waiting itself runs in
tests/test_sitl_side_by_side.py)."""

from __future__ import annotations

import sys
from pathlib import Path
from types import ModuleType, SimpleNamespace
from typing import Any

import pytest
from module_by_path import load_module

START_PY = Path(__file__).resolve().parents[1] / "scripts" / "sitl" / "start.py"


@pytest.fixture(scope="module")
def readiness() -> ModuleType:
    load_module("skyquill_sitl_start", START_PY)
    return sys.modules["readiness"]  # as start.py imported it


def msg(kind: str, **fields: Any) -> SimpleNamespace:
    return SimpleNamespace(get_type=lambda: kind, **fields)


def instance(kind: str, *, mocap: bool, imu_vibration: float | None = None) -> Any:
    sitl = sys.modules["instances"]
    return sitl.Instance(kind, 0, 1, (0.0, 0.0, 0.0), Path("x"), Path("d"), 47610, mocap=mocap,
                         imu_vibration=imu_vibration)  # fmt: skip


def test_arducopter_on_mocap_is_ready_with_its_boot_parameters_and_its_ekf_aligned(
    readiness: ModuleType,
) -> None:
    """No local position and no pre-arm: those wait for the mocap the agent forwards. No GPS
    fix either: it boots without a GPS, whose origin would race the agent's."""
    inst = instance("ardupilot", mocap=True)
    state = readiness.Readiness("ardupilot", True, sys.modules["instances"].boot_params(inst))
    assert state.params_expected["GPS1_TYPE"] == 0.0
    state.update(msg("ESTIMATOR_STATUS", flags=1))  # PX4's message: not this autopilot's
    for name, value in state.params_expected.items():
        state.update(msg("PARAM_VALUE", param_id=name, param_value=value))
    assert not state.ready() and state.conditions()["EKF attitude (EKF_STATUS_REPORT)"] is False
    state.update(msg("EKF_STATUS_REPORT", flags=0x0))
    assert not state.ready()
    state.update(msg("EKF_STATUS_REPORT", flags=0x1))  # attitude; no position yet
    assert state.ready()
    state.update(msg("PARAM_VALUE", param_id="VISO_TYPE", param_value=0.0))
    assert state.params_missing() == ["VISO_TYPE"] and not state.ready()


def test_px4_on_mocap_reads_back_its_environment_parameters(readiness: ModuleType) -> None:
    inst = instance("px4", mocap=True, imu_vibration=0.0)
    expected = sys.modules["instances"].boot_params(inst)
    assert expected == {"EKF2_ASP_DELAY": 0.0, "EKF2_DELAY_MAX": 20.0, "SIH_IMU_VIB": 0.0}
    state = readiness.Readiness("px4", True, expected)
    for message in (msg("GPS_RAW_INT", fix_type=3), msg("ESTIMATOR_STATUS", flags=0x1)):
        state.update(message)
    state.update(msg("PARAM_VALUE", param_id="EKF2_DELAY_MAX\0\0", param_value=20.0))
    state.update(msg("PARAM_VALUE", param_id="EKF2_ASP_DELAY", param_value=0.0))
    assert state.params_missing() == ["SIH_IMU_VIB"]
    state.update(msg("PARAM_VALUE", param_id="SIH_IMU_VIB", param_value=1e-9))
    assert state.ready()


def test_a_vehicle_without_mocap_waits_until_it_could_arm(readiness: ModuleType) -> None:
    state = readiness.Readiness("ardupilot", False, {})
    for message in (msg("GPS_RAW_INT", fix_type=3), msg("EKF_STATUS_REPORT", flags=0x1),
                    msg("LOCAL_POSITION_NED")):  # fmt: skip
        state.update(message)
    assert state.conditions() == {"gps fix": True, "local position": True, "pre-arm good": False}
    state.update(msg("SYS_STATUS", onboard_control_sensors_health=0x10000000))
    assert state.ready()
    state.update(msg("GPS_RAW_INT", fix_type=2))  # lost its fix
    assert not state.ready()


def test_the_summary_says_what_was_waited_for_and_what_waits_for_the_agent(
    readiness: ModuleType,
) -> None:
    state = readiness.Readiness("ardupilot", True, {"VISO_TYPE": 1.0})
    state.update(msg("STATUSTEXT", text="PreArm: VisOdom: not healthy"))
    summary = state.summary()
    assert summary.startswith("boot parameters VISO_TYPE, EKF attitude")
    assert summary.endswith("wait for the agent's mocap (last: 'PreArm: VisOdom: not healthy')")
    assert readiness.Readiness("px4", False, {}).summary() == (
        "gps fix, local position, pre-arm good"
    )

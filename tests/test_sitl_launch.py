"""scripts/sitl/start.py: which SITL instance a show's vehicle is, and how it is started (pure
parts; the processes themselves run in the conformance suite's ``-m sitl`` tests)."""

from __future__ import annotations

import importlib.util
import math
import os
import sys
from dataclasses import replace
from pathlib import Path
from types import ModuleType

import pytest

from vehicle_agent.backends.mavlink_params import PX4_DELAY_MAX_MS, mocap_params

START_PY = Path(__file__).resolve().parents[1] / "scripts" / "sitl" / "start.py"


@pytest.fixture(scope="module")
def launch() -> ModuleType:
    name = "skyquill_sitl_start"
    module = sys.modules.get(name)
    if module is None:
        spec = importlib.util.spec_from_file_location(name, START_PY)
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize(
    ("url", "kind", "index"),
    [
        ("tcp:127.0.0.1:5760", "ardupilot", 0),
        ("tcp:127.0.0.1:5790", "ardupilot", 3),
        ("udpin:127.0.0.1:14540", "px4", 0),
        ("udpin:127.0.0.1:14549", "px4", 9),
    ],
)
def test_a_url_names_its_autopilot_and_instance(
    launch: ModuleType, url: str, kind: str, index: int
) -> None:
    assert launch.url_instance(url) == (kind, index)
    inst = launch.Instance(kind, index, index + 1, (0.0, 0.0, 0.0), Path("x"), Path("d"))
    assert inst.url == url


@pytest.mark.parametrize(
    "url", ["tcp:127.0.0.1:5762", "udp:127.0.0.1:14540", "udpin:127.0.0.1:14550", "tcp:h:x"]
)
def test_a_url_of_no_sitl_instance_is_refused_saying_what_is_expected(
    launch: ModuleType, url: str
) -> None:
    with pytest.raises(launch.SitlError, match="mavlink_url"):
        launch.url_instance(url)


def test_homes_are_placed_east_and_north_of_the_reference(launch: ModuleType) -> None:
    lat0, lon0, alt0 = launch.REFERENCE_LLA
    lat, lon, alt = launch.home_lla((10.0, 20.0, 1.5))
    north_m = math.radians(lat - lat0) * launch.EARTH_RADIUS_M
    east_m = math.radians(lon - lon0) * launch.EARTH_RADIUS_M * math.cos(math.radians(lat0))
    assert north_m == pytest.approx(20.0, abs=1e-6) and east_m == pytest.approx(10.0, abs=1e-6)
    assert alt == pytest.approx(alt0 + 1.5)


def test_px4_instances_must_use_the_system_id_px4_forces(launch: ModuleType) -> None:
    inst = launch.Instance("px4", 1, 5, (0.0, 0.0, 0.0), Path("px4"), Path("d"))
    with pytest.raises(launch.SitlError, match="MAV_SYS_ID 2"):
        launch.check_instance(inst)


def test_arducopter_starts_with_its_defaults_sysid_home_and_serial0_not_waiting(
    launch: ModuleType, tmp_path: Path
) -> None:
    binary = tmp_path / "build" / "sitl" / "bin" / "arducopter"
    binary.parent.mkdir(parents=True)
    binary.write_text("")
    defaults = tmp_path / "Tools" / "autotest" / "default_params" / "copter.parm"
    defaults.parent.mkdir(parents=True)
    defaults.write_text("")
    inst = launch.Instance("ardupilot", 2, 9, (-35.0, 149.0, 584.0), binary, tmp_path / "run")
    launch.check_instance(inst)
    argv, _ = launch.command(inst)
    pairs = dict(zip(argv[1::2], argv[2::2], strict=False))
    assert pairs["-I"] == "2" and pairs["--sysid"] == "9"
    assert pairs["--defaults"] == str(defaults.resolve())
    assert pairs["--home"] == "-35.0000000,149.0000000,584.00,0"
    assert argv[-2:] == ["--serial0", "tcp:0"]
    with_mocap = launch.command(replace(inst, mocap=True))[0]
    mocap_parm = str(tmp_path / "run" / "mocap.parm")
    assert with_mocap[with_mocap.index("--defaults") + 1] == f"{defaults.resolve()},{mocap_parm}"


def test_arducopter_boots_with_the_mocap_sources_the_agent_sets(launch: ModuleType) -> None:
    # Set only at connect, a GPS fix that came first gave the EKF its origin and it never used
    # the mocap: the boot defaults must be what the agent sets (position alone).
    booted = dict(line.split() for line in launch.MOCAP_BOOT_PARAMS.splitlines())
    agent = {spec.name: spec.value for spec in mocap_params("ardupilot")}
    assert booted.keys() == {"VISO_TYPE"} | {k for k in agent if k.startswith("EK3_SRC1_")}
    assert all(float(value) == agent[name] for name, value in booted.items())


def test_px4_starts_sih_at_its_home(launch: ModuleType, tmp_path: Path) -> None:
    binary = tmp_path / "build" / "px4_sitl_default" / "bin" / "px4"
    inst = launch.Instance("px4", 1, 2, (-35.5, 149.25, 590.0), binary, tmp_path / "run")
    argv, env = launch.command(inst)
    assert argv[1:4] == ["-i", "1", "-d"] and argv[4].endswith("px4_sitl_default/etc")
    assert env["PX4_SIMULATOR"] == "sihsim" and env["PX4_SIM_MODEL"] == "sihsim_quadx"
    assert (env["PX4_HOME_LAT"], env["PX4_HOME_ALT"]) == ("-35.5000000", "590.00")
    assert "PX4_PARAM_EKF2_DELAY_MAX" not in env
    _, with_mocap = launch.command(replace(inst, mocap=True))
    # read at boot, checked by the agent at connect: both sides agree
    assert float(with_mocap["PX4_PARAM_EKF2_DELAY_MAX"]) == PX4_DELAY_MAX_MS


def test_a_missing_binary_variable_is_named(
    launch: ModuleType, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("SKYQUILL_PX4_SITL", raising=False)
    with pytest.raises(launch.SitlError, match="SKYQUILL_PX4_SITL not set"):
        launch.binary_for("px4")
    monkeypatch.setenv("SKYQUILL_PX4_SITL", os.devnull)
    with pytest.raises(launch.SitlError, match="not an executable file"):
        launch.binary_for("px4")


def test_a_px4_research_airframe_needs_a_binary_with_the_vibration_parameter(
    launch: ModuleType, tmp_path: Path
) -> None:
    binary = tmp_path / "build" / "px4_sitl_default" / "bin" / "px4"
    binary.parent.mkdir(parents=True)
    binary.write_bytes(b"\0" * 100 + b"SIH_T_TAU\0" + b"\0" * 100)
    inst = launch.Instance("px4", 0, 1, (0.0, 0.0, 0.0), binary, tmp_path / "run", mocap=True)
    launch.check_instance(inst)  # SIH's own vibration: any binary
    research = replace(inst, imu_vibration=0.0)
    with pytest.raises(launch.SitlError, match="has no SIH_IMU_VIB: build it with scripts/sitl"):
        launch.check_instance(research)
    # the name read across the boundary between two chunks of the file
    binary.write_bytes(b"\0" * 5 + launch.PX4_VIBRATION_PARAM.encode() + b"\0")
    assert launch.binary_has(binary, b"SIH_IMU_VIB", chunk_bytes=8)
    assert not launch.binary_has(binary, b"SIH_IMU_VIBX", chunk_bytes=8)
    launch.check_instance(research)
    assert launch.command(research)[1]["PX4_PARAM_SIH_IMU_VIB"] == "0"
    assert "PX4_PARAM_SIH_IMU_VIB" not in launch.command(inst)[1]
    with pytest.raises(launch.SitlError, match="PX4 SIH only"):
        launch.check_instance(replace(research, kind="ardupilot", imu_vibration=0.5))


def test_px4_vehicles_on_mocap_fly_a_research_airframe_unless_told(
    launch: ModuleType, tmp_path: Path
) -> None:
    binary = tmp_path / "px4"
    binary.write_bytes(b"SIH_IMU_VIB")
    binary.chmod(0o755)
    show = Path(__file__).resolve().parents[1] / "shows" / "sitl-px4.yaml"
    found = launch.show_instances(show, tmp_path, {"ardupilot": None, "px4": str(binary)})
    assert [inst.imu_vibration for _, inst in found] == [0.0] * len(found)
    assert all(inst.mocap for _, inst in found)
    stock = launch.show_instances(show, tmp_path, {"ardupilot": None, "px4": str(binary)}, None)
    assert [inst.imu_vibration for _, inst in stock] == [None] * len(found)

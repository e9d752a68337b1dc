"""scripts/sitl/start.py and instances.py: which autopilot and port a show's vehicle names, which
instance number is free, how an instance is started (pure parts and the locks; the SITL
processes themselves run in tests/test_sitl_side_by_side.py and the conformance suite)."""

from __future__ import annotations

import contextlib
import math
import os
import re
import signal
import socket
import struct
import subprocess
import sys
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path
from types import ModuleType

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from module_by_path import load_module
from processes import running
from test_sitl_side_by_side import free_ports, with_ports

from vehicle_agent.backends.mavlink.params import PX4_DELAY_MAX_MS, mocap_params

ROOT = Path(__file__).resolve().parents[1]
START_PY = ROOT / "scripts" / "sitl" / "start.py"


@pytest.fixture(scope="module")
def launch() -> ModuleType:
    return load_module("skyquill_sitl_start", START_PY)


@pytest.fixture(scope="module")
def sitl(launch: ModuleType) -> ModuleType:
    """scripts/sitl/instances.py, as start.py imported it."""
    return sys.modules["instances"]


def copter_binary(root: Path) -> Path:
    """A fake ArduCopter build: a binary that sleeps, beside its copter.parm."""
    binary = root / "build" / "sitl" / "bin" / "arducopter"
    binary.parent.mkdir(parents=True)
    binary.write_text("#!/bin/sh\nexec sleep 60\n")
    binary.chmod(0o755)
    defaults = root / "Tools" / "autotest" / "default_params" / "copter.parm"
    defaults.parent.mkdir(parents=True)
    defaults.write_text("")
    return binary


def px4_binary(root: Path, *, edited: bool = True, names: bytes = b"SIH_IMU_VIB") -> Path:
    """A fake PX4 build whose startup scripts read the port variables when ``edited``."""
    binary = root / "build" / "px4_sitl_default" / "bin" / "px4"
    binary.parent.mkdir(parents=True)
    binary.write_bytes(b"\0" + names + b"\0")
    binary.chmod(0o755)
    init = root / "build" / "px4_sitl_default" / "etc" / "init.d-posix"
    init.mkdir(parents=True)
    used = "${PX4_SYS_ID:-1} ${PX4_OFFBOARD_REMOTE_PORT:-2} ${PX4_GCS_REMOTE_PORT:+3}"
    (init / "rcS").write_text(used if edited else "param set MAV_SYS_ID $((px4_instance+1))")
    (init / "px4-rc.mavlink").write_text("")
    return binary


@pytest.mark.parametrize(
    ("url", "kind", "port"),
    [
        ("tcp:127.0.0.1:5760", "ardupilot", 5760),
        ("tcp:127.0.0.1:47610", "ardupilot", 47610),
        ("tcp:localhost:1001", "ardupilot", 1001),
        ("udpin:127.0.0.1:14540", "px4", 14540),
        ("udpin:127.0.0.1:47650", "px4", 47650),
    ],
)
def test_a_url_names_its_autopilot_and_the_agent_port_any_port(
    sitl: ModuleType, url: str, kind: str, port: int
) -> None:
    assert sitl.url_kind_port(url) == (kind, port)
    inst = sitl.Instance(kind, 3, 1, (0.0, 0.0, 0.0), Path("x"), Path("d"), port)
    assert inst.url == url.replace("localhost", "127.0.0.1")


@pytest.mark.parametrize(
    "url",
    [
        "tcp:127.0.0.1:1000",  # ArduPilot takes it as an offset from its base port
        "udp:127.0.0.1:14540",
        "tcp:192.168.1.5:5760",  # the instances listen on loopback only
        "tcp:h:x",
        "udpin:127.0.0.1:65536",
        "udpin:127.0.0.1:",
    ],
)
def test_a_url_of_no_sitl_instance_is_refused_saying_what_is_expected(
    sitl: ModuleType, url: str
) -> None:
    with pytest.raises(sitl.SitlError, match=r"mavlink_url .* expected tcp:127\.0\.0\.1:PORT"):
        sitl.url_kind_port(url)


@pytest.fixture
def held() -> Iterator[list[socket.socket]]:
    """Sockets a test binds to make ports busy; closed after it."""
    sockets: list[socket.socket] = []
    yield sockets
    for sock in sockets:
        sock.close()


def bind(held: list[socket.socket], protocol: str, port: int) -> None:
    kind = socket.SOCK_STREAM if protocol == "tcp" else socket.SOCK_DGRAM
    sock = socket.socket(socket.AF_INET, kind)
    sock.bind(("127.0.0.1", port))  # as the SITLs bind: loopback
    held.append(sock)


def test_a_tcp_port_a_finished_show_left_in_time_wait_is_free(sitl: ModuleType) -> None:
    # ArduCopter SITL listens with SO_REUSEADDR: the TIME_WAIT of its agent's closed link is no
    # obstacle to the next show, and a listener still there is
    with socket.socket() as listener:
        listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        listener.bind(("127.0.0.1", 0))
        listener.listen()
        port = listener.getsockname()[1]
        with socket.create_connection(("127.0.0.1", port)) as agent:
            served, _ = listener.accept()
            served.close()  # the SITL side closes first: its port goes to TIME_WAIT
            agent.recv(1)
        assert not sitl.port_free("tcp", port)
    assert sitl.port_free("tcp", port)


@pytest.mark.parametrize("kind", ["ardupilot", "px4"])
def test_a_number_with_a_busy_port_is_skipped(
    sitl: ModuleType, tmp_path: Path, held: list[socket.socket], kind: str
) -> None:
    first, fd = sitl.claim(kind, lock_dir=tmp_path)
    os.close(fd)  # unclaimed again
    for protocol, port in sitl.instance_ports(kind, first):
        assert sitl.port_free(protocol, port)
    protocol, port = sitl.instance_ports(kind, first)[-1]
    bind(held, protocol, port)
    assert not sitl.port_free(protocol, port)
    index, fd = sitl.claim(kind, lock_dir=tmp_path)
    os.close(fd)
    assert index > first
    assert port not in [p for _, p in sitl.instance_ports(kind, index)]


def test_a_number_whose_ports_a_show_uses_is_skipped(sitl: ModuleType, tmp_path: Path) -> None:
    first, fd = sitl.claim("px4", lock_dir=tmp_path)
    os.close(fd)
    probe = sitl.probe_port("px4", first)
    index, fd = sitl.claim("px4", avoid_ports=[probe], lock_dir=tmp_path)
    os.close(fd)
    assert index > first


def test_without_a_show_port_the_agent_port_of_the_number_must_be_free(
    sitl: ModuleType, tmp_path: Path, held: list[socket.socket]
) -> None:
    first, fd = sitl.claim("ardupilot", default_agent=True, lock_dir=tmp_path)
    os.close(fd)
    bind(held, "tcp", sitl.default_agent_port("ardupilot", first))
    assert sitl.claim("ardupilot", lock_dir=tmp_path)[0] == first  # a show gives its own port
    index, fd = sitl.claim("ardupilot", default_agent=True, lock_dir=tmp_path)
    os.close(fd)
    assert index > first


def test_a_claimed_number_stays_taken_while_the_process_started_on_it_runs(
    launch: ModuleType, sitl: ModuleType, tmp_path: Path
) -> None:
    """start() hands the lock to the SITL process: the number is taken exactly as long as the
    instance runs, also by another start.py started at the same moment."""
    index, fd = sitl.claim("ardupilot", lock_dir=tmp_path)
    other, other_fd = sitl.claim("ardupilot", lock_dir=tmp_path)  # claimed: the next one
    os.close(other_fd)
    assert other != index
    binary = copter_binary(tmp_path / "src")
    inst = sitl.Instance("ardupilot", index, 1, (0.0, 0.0, 0.0), binary, tmp_path / "run",
                         47610, claim_fd=fd)  # fmt: skip
    proc = launch.start(inst)
    try:
        with pytest.raises(OSError):
            os.fstat(fd)  # this process's copy is closed
        assert sitl.claim("ardupilot", lock_dir=tmp_path)[0] != index
    finally:
        launch.stop(proc)
    again, fd = sitl.claim("ardupilot", lock_dir=tmp_path)
    os.close(fd)
    assert again == index


def test_a_crashing_arducopter_finds_its_stack_dumper_in_its_folder(
    launch: ModuleType, sitl: ModuleType, tmp_path: Path
) -> None:
    """ArduPilot SITL runs ``sh dumpstack.sh PID`` in its folder when it dies of a signal: a
    floating point exception left only "cannot open dumpstack.sh" until start.py put it there."""
    binary = copter_binary(tmp_path / "src")
    script = tmp_path / "src" / "Tools" / "scripts" / "dumpstack.sh"
    script.parent.mkdir(parents=True)
    script.write_text("gdb -batch --pid $1\n")
    index, fd = sitl.claim("ardupilot", lock_dir=tmp_path)
    inst = sitl.Instance("ardupilot", index, 1, (0.0, 0.0, 0.0), binary, tmp_path / "run",
                         47610, claim_fd=fd)  # fmt: skip
    launch.stop(launch.start(inst))
    assert (tmp_path / "run" / "dumpstack.sh").read_text() == script.read_text()


def test_a_number_a_px4_runs_as_is_skipped(
    sitl: ModuleType, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """PX4 keeps a POSIX lock on /tmp/px4_lock-N while it runs; another ``-i N`` exits."""
    monkeypatch.setattr(sitl, "PX4_LOCK_FILE", str(tmp_path / "px4_lock-{n}"))
    first, fd = sitl.claim("px4", lock_dir=tmp_path)
    os.close(fd)
    lock = tmp_path / f"px4_lock-{first}"
    holder = subprocess.Popen(
        [sys.executable, "-c", "import fcntl, sys, time; f = open(sys.argv[1], 'w'); "
         "fcntl.lockf(f, fcntl.LOCK_EX); print('locked', flush=True); time.sleep(60)", str(lock)],
        stdout=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        assert holder.stdout is not None and holder.stdout.readline() == "locked\n"
        assert sitl.px4_running(first) and not sitl.px4_running(first + 1)
        index, fd = sitl.claim("px4", lock_dir=tmp_path)
        os.close(fd)
        assert index != first
    finally:
        holder.kill()
        holder.wait()
    assert lock.exists() and not sitl.px4_running(first)


def test_homes_are_placed_east_and_north_of_the_reference(sitl: ModuleType) -> None:
    lat0, lon0, alt0 = sitl.REFERENCE_LLA
    lat, lon, alt = sitl.home_lla((10.0, 20.0, 1.5))
    north_m = math.radians(lat - lat0) * sitl.EARTH_RADIUS_M
    east_m = math.radians(lon - lon0) * sitl.EARTH_RADIUS_M * math.cos(math.radians(lat0))
    assert north_m == pytest.approx(20.0, abs=1e-6) and east_m == pytest.approx(10.0, abs=1e-6)
    assert alt == pytest.approx(alt0 + 1.5)


@settings(max_examples=300, deadline=None)
@given(st.floats(-89.0, 89.0).filter(lambda d: abs(d) > 1e-3), st.integers(0, 1))
def test_a_px4_home_sits_half_way_along_the_truths_step_so_its_truncation_is_unbiased(
    sitl: ModuleType, degrees: float, as_longitude: int
) -> None:
    """PX4 sends the truth as int32(deg * 1e7), cut towards zero: a vehicle resting at a home
    half-way along its step reads half a step short, as a flight's samples do on average, so the
    show frame anchored on it is unbiased (bias = place in the step - 1/2)."""
    value = sitl.px4_sih_degrees(degrees * (2.0 if as_longitude else 1.0))
    assert struct.unpack("<f", struct.pack("<f", value))[0] == value  # SIH_LOC_*0 is a float32
    steps = abs(value) * 1e7
    assert abs(steps % 1.0 - 0.5) < 0.1  # at most a tenth of a step (1.1 mm) of bias
    assert abs(value - degrees * (2.0 if as_longitude else 1.0)) < 40e-5  # within ~45 m
    assert float(f"{value:.10f}") == pytest.approx(value, abs=1e-10)  # as PX4_HOME_LAT says it


def test_px4_starts_at_its_home_half_way_along_the_truths_step(
    sitl: ModuleType, tmp_path: Path
) -> None:
    inst = sitl.Instance("px4", 3, 9, sitl.home_lla((1.0, -1.2, 0.0)), tmp_path / "px4",
                         tmp_path / "run", 24540)  # fmt: skip
    _, env = sitl.command(inst)
    for name in ("PX4_HOME_LAT", "PX4_HOME_LON"):
        assert abs(abs(float(env[name])) * 1e7 % 1.0 - 0.5) < 0.1, env[name]


def test_arducopter_listens_for_the_agent_on_the_show_port_and_for_start_py_on_serial2(
    sitl: ModuleType, tmp_path: Path
) -> None:
    binary = copter_binary(tmp_path)
    inst = sitl.Instance("ardupilot", 2, 9, (-35.0, 149.0, 584.0), binary, tmp_path / "run", 47610)
    sitl.check_instance(inst)
    argv, _ = sitl.command(inst)
    pairs = {flag: argv[k + 1] for k, flag in enumerate(argv[:-1]) if flag.startswith("-")}
    assert pairs["-I"] == "2" and pairs["--sysid"] == "9"
    assert pairs["--serial0"] == "tcp:47610"  # above 1000: the port itself, not waiting
    assert pairs["--serial2"] == "tcp:5783" and inst.probe_url == "tcp:127.0.0.1:5783"
    assert ("tcp", 5783) in sitl.instance_ports("ardupilot", 2)
    assert pairs["--defaults"] == str(tmp_path / "Tools/autotest/default_params/copter.parm")
    assert "--wipe" in argv
    assert pairs["--home"] == "-35.0000000,149.0000000,584.00,0"
    with_mocap = sitl.command(replace(inst, mocap=True))[0]
    mocap_parm = str(tmp_path / "run" / "mocap.parm")
    assert with_mocap[with_mocap.index("--defaults") + 1] == f"{pairs['--defaults']},{mocap_parm}"


def test_arducopter_boots_with_the_mocap_sources_the_agent_sets(sitl: ModuleType) -> None:
    # Set only at connect, a GPS fix that came first gave the EKF its origin and it never used
    # the mocap: the boot defaults must be what the agent sets (position alone).
    booted = dict(line.split() for line in sitl.mocap_parm_text().splitlines())
    agent = {spec.name: spec.value for spec in mocap_params("ardupilot")}
    # And no GPS: indoors a GPS has no fix; the simulated one would set the origin first.
    assert booted.pop("GPS1_TYPE") == "0"
    assert booted.keys() == {"VISO_TYPE"} | {k for k in agent if k.startswith("EK3_SRC1_")}
    assert all(float(value) == agent[name] for name, value in booted.items())


def test_px4_gets_its_system_id_and_both_ports_from_its_environment(
    sitl: ModuleType, tmp_path: Path
) -> None:
    binary = px4_binary(tmp_path)
    inst = sitl.Instance("px4", 1, 7, (-35.5, 149.25, 590.0), binary, tmp_path / "run", 47650)
    sitl.check_instance(inst)
    argv, env = sitl.command(inst)
    assert argv[1:4] == ["-i", "1", "-d"] and argv[4].endswith("px4_sitl_default/etc")
    assert (env["PX4_SYS_ID"], env["PX4_OFFBOARD_REMOTE_PORT"]) == ("7", "47650")
    assert env["PX4_GCS_REMOTE_PORT"] == "14561" and inst.probe_url == "udpin:127.0.0.1:14561"
    assert env["PX4_SIMULATOR"] == "sihsim" and env["PX4_SIM_MODEL"] == "sihsim_quadx"
    assert float(env["PX4_HOME_LAT"]) == pytest.approx(-35.5, abs=40e-5)  # half-way along a step
    assert env["PX4_HOME_ALT"] == "590.00"
    assert "PX4_PARAM_EKF2_DELAY_MAX" not in env
    _, with_mocap = sitl.command(replace(inst, mocap=True))
    # read at boot, checked by the agent at connect: both sides agree
    assert float(with_mocap["PX4_PARAM_EKF2_DELAY_MAX"]) == PX4_DELAY_MAX_MS


def test_a_px4_whose_scripts_ignore_the_port_variables_is_refused(
    sitl: ModuleType, tmp_path: Path
) -> None:
    binary = px4_binary(tmp_path, edited=False)
    inst = sitl.Instance("px4", 0, 1, (0.0, 0.0, 0.0), binary, tmp_path / "run", 47650)
    with pytest.raises(sitl.SitlError, match=r"takes no PX4_SYS_ID.*scripts/sitl/build\.py"):
        sitl.check_instance(inst)


def test_a_missing_binary_variable_is_named(
    sitl: ModuleType, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("SKYQUILL_PX4_SITL", raising=False)
    with pytest.raises(sitl.SitlError, match="SKYQUILL_PX4_SITL not set"):
        sitl.binary_for("px4")
    monkeypatch.setenv("SKYQUILL_PX4_SITL", os.devnull)
    with pytest.raises(sitl.SitlError, match="not an executable file"):
        sitl.binary_for("px4")


def test_px4s_estimator_is_told_the_stock_airframes_imu_noise(
    sitl: ModuleType, tmp_path: Path
) -> None:
    """SIH's roll gyro, 0.14 rad/s a sample at 250 Hz, over EKF2's 10 ms step, and the velocity
    pulled to the mocap's within 0.03 s, not carried on its vibrating accelerometer; the research
    airframe's gyro (0.01) is within PX4's default 0.015, its velocity left to the agent."""
    inst = sitl.Instance("px4", 0, 1, (0.0, 0.0, 0.0), px4_binary(tmp_path), tmp_path / "run",
                         47650, mocap=True)  # fmt: skip
    assert sitl.boot_params(inst)["EKF2_GYR_NOISE"] == pytest.approx(0.14 / math.sqrt(2.5), 1e-2)
    assert sitl.command(inst)[1]["PX4_PARAM_EKF2_GYR_NOISE"] == "0.089"
    assert sitl.command(inst)[1]["PX4_PARAM_EKF2_TAU_VEL"] == "0.03"
    research = sitl.boot_params(replace(inst, imu_vibration=0.0))
    assert "EKF2_GYR_NOISE" not in research and "EKF2_TAU_VEL" not in research


def test_a_px4_research_airframe_needs_a_binary_with_the_vibration_parameter(
    sitl: ModuleType, tmp_path: Path
) -> None:
    binary = px4_binary(tmp_path, names=b"SIH_T_TAU")
    inst = sitl.Instance("px4", 0, 1, (0.0, 0.0, 0.0), binary, tmp_path / "run", 47650,
                         mocap=True)  # fmt: skip
    sitl.check_instance(inst)  # SIH's own vibration: any binary
    research = replace(inst, imu_vibration=0.0)
    with pytest.raises(sitl.SitlError, match="has no SIH_IMU_VIB: build it with scripts/sitl"):
        sitl.check_instance(research)
    # the name read across the boundary between two chunks of the file
    binary.write_bytes(b"\0" * 5 + sitl.PX4_VIBRATION_PARAM.encode() + b"\0")
    assert sitl.binary_has(binary, b"SIH_IMU_VIB", chunk_bytes=8)
    assert not sitl.binary_has(binary, b"SIH_IMU_VIBX", chunk_bytes=8)
    sitl.check_instance(research)
    assert sitl.command(research)[1]["PX4_PARAM_SIH_IMU_VIB"] == "0"
    assert "PX4_PARAM_SIH_IMU_VIB" not in sitl.command(inst)[1]
    with pytest.raises(sitl.SitlError, match="PX4 SIH only"):
        sitl.check_instance(replace(research, kind="ardupilot", imu_vibration=0.5))


def test_a_show_claims_one_number_per_vehicle_on_the_ports_it_names(
    launch: ModuleType, tmp_path: Path
) -> None:
    binary = px4_binary(tmp_path)
    show = tmp_path / "show.yaml"
    text, count = with_ports((ROOT / "shows" / "sitl-px4.yaml").read_text(), [47650, 47651])
    assert count == 2
    show.write_text(text)
    found = launch.show_instances(show, tmp_path / "run", {"ardupilot": None, "px4": str(binary)})
    try:
        assert [inst.agent_port for _, inst in found] == [47650, 47651]
        assert len({inst.index for _, inst in found}) == len(found)
        assert [inst.run_dir.name for _, inst in found] == [vehicle for vehicle, _ in found]
        assert [inst.imu_vibration for _, inst in found] == [0.0] * len(found)  # research
        assert all(inst.mocap for _, inst in found)
    finally:
        for _, inst in found:
            os.close(inst.claim_fd)


def test_start_py_imports_no_project_package_at_module_level() -> None:
    """tests/conformance/sitl_targets.py and the scripts load it by path, before the project."""
    code = (
        "import importlib.util, sys\n"
        f"spec = importlib.util.spec_from_file_location('s', {str(START_PY)!r})\n"
        "m = importlib.util.module_from_spec(spec); sys.modules['s'] = m\n"
        "spec.loader.exec_module(m)\n"
        "print(sorted({'showfile', 'vehicle_agent', 'planner', 'bus'} & set(sys.modules)))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_an_arducopter_show_port_in_use_is_named_before_anything_starts(
    launch: ModuleType, tmp_path: Path, held: list[socket.socket]
) -> None:
    binary = copter_binary(tmp_path)
    bind(held, "tcp", 0)  # a port the kernel gives out, now held
    busy = int(held[0].getsockname()[1])
    text, count = with_ports((ROOT / "shows" / "sitl-ardupilot.yaml").read_text(), [busy, busy + 1])
    assert count == 2
    (tmp_path / "show.yaml").write_text(text)
    binaries = {"ardupilot": str(binary), "px4": None}
    with pytest.raises(launch.SitlError, match=rf"uav1: tcp:127\.0\.0\.1:{busy} is in use"):
        launch.show_instances(tmp_path / "show.yaml", tmp_path / "run", binaries)


@pytest.mark.parametrize("stop_signal", [signal.SIGINT, signal.SIGTERM])
def test_start_py_stops_its_instances_on_a_signal_even_when_started_with_sigint_ignored(
    tmp_path: Path, stop_signal: int
) -> None:
    """A start.py started in the background of a script inherits SIGINT ignored, and Python
    then sets no handler of its own: ``kill -INT`` left it and its SITL instances running
    (tests/test_sitl_side_by_side.py, from a background shell). Here its two instances are fake
    ArduCopters that never answer, so it is still waiting for them when the signal comes."""
    binary = copter_binary(tmp_path)
    ports = free_ports("tcp", 2)
    text, count = with_ports((ROOT / "shows" / "sitl-ardupilot.yaml").read_text(), ports)
    assert count == 2
    (tmp_path / "show.yaml").write_text(text)
    proc = subprocess.Popen(
        [sys.executable, str(START_PY), str(tmp_path / "show.yaml"), "--run-dir",
         str(tmp_path / "run"), "--arducopter", str(binary), "--ready-timeout", "60"],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN),
    )  # fmt: skip
    assert proc.stdout is not None
    pids: list[int] = []
    try:
        started = [proc.stdout.readline() for _ in range(2)]
        assert all("ardupilot instance" in line for line in started), started
        pids = [int(pid) for pid in re.findall(r"pid (\d+)", "".join(started))]
        assert len(pids) == 2, started
        proc.send_signal(stop_signal)
        out, _ = proc.communicate(timeout=30)
        left_running = [pid for pid in pids if running(pid)]
    finally:  # nothing left running whatever failed
        for pid in [proc.pid, *pids]:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
    assert proc.returncode == 0, out
    assert "stopped 2 instance(s)" in out
    assert left_running == []

"""Start real autopilot SITL instances (ArduCopter, PX4 SIH) for a show; stop them cleanly.

    .venv/bin/python scripts/sitl/start.py shows/sitl-ardupilot.yaml   # Ctrl-C stops them

One instance per ``backend: mavlink`` vehicle of the show. The vehicle's ``mavlink_url`` says
which autopilot and where the agent talks to it, any free port (scripts/sitl/instances.py):

- ArduCopter: ``tcp:127.0.0.1:PORT``, its SERIAL0 listening on PORT; system id
  ``mavlink_system_id`` (``--sysid``); binary from ``--arducopter`` or $SKYQUILL_ARDUCOPTER_SITL;
- PX4 SIH quadrotor: ``udpin:127.0.0.1:PORT``, its offboard link sending to PORT; system id
  ``mavlink_system_id`` (PX4_SYS_ID); binary from ``--px4`` or $SKYQUILL_PX4_SITL, built by
  scripts/sitl/build.py (whose edits let PX4 take both from the environment).

start.py picks each instance's number itself among those whose ports are free right now, so two
shows, or a show and a test, run side by side. It waits until every instance is ready on a link
of its own (scripts/sitl/readiness.py says what ready means, with and without mocap), never on
the agent's: start it before or after ``skyquill up``.

A PX4 vehicle that forwards mocap flies a research airframe: SIH's armed IMU noise at its
disarmed level (``SIH_IMU_VIB`` 0, a parameter scripts/sitl/build.py adds to SIH;
``--px4-imu-vibration`` says otherwise). SIH's stock airframe vibrates too much for centimetre
writing (scripts/sitl/source_edits.py says what was measured).

Each instance starts at the geodetic point of the vehicle's ``home_m_enu`` (east/north metres from
a reference point), which is also its LOCAL_NED origin, and runs in its own directory
``--run-dir``/VEHICLE (eeprom, logs, parameters; its console output in ``console.log``; an
ArduCopter that crashes writes its stack there, ``dumpstack.sh_arducopter.PID.out``), with its
parameters at their defaults: ArduCopter's wiped to Tools/autotest/default_params/copter.parm,
PX4's saved ones removed. Use binaries whose listeners are bound to 127.0.0.1 (README, "Real
autopilot SITL").

This file is also imported by path (tests/conformance/sitl_targets.py, the SITL tests and
scripts): keep it free of project imports at module level.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from instances import (  # scripts/sitl/, beside this file
    ENV_BINARY,
    MOCAP_PARM,
    PX4_VIBRATION_PARAM,
    Instance,
    Kind,
    SitlError,
    as_kind,
    binary_for,
    binary_has,
    check_instance,
    claim,
    command,
    default_agent_port,
    home_lla,
    mocap_parm_text,
    port_free,
    url_kind_port,
)
from readiness import STOP_REQUESTED, wait_ready

__all__ = [  # what the tests and the other scripts use of the launcher
    "ENV_BINARY", "PX4_VIBRATION_PARAM", "READY_TIMEOUT_S", "RESEARCH_AIRFRAME_VIBRATION",
    "Instance", "SitlError", "as_kind", "binary_for", "binary_has", "claim_instance",
    "home_lla", "show_instances", "start", "stop", "wait_ready",
]  # fmt: skip

RESEARCH_AIRFRAME_VIBRATION = 0.0
"""SIH_IMU_VIB of a vehicle on mocap: SIH's disarmed noise level (0.1 m/s^2, 0.01 rad/s)."""
READY_TIMEOUT_S = 180.0
"""Longest wait for a fresh instance to be ready, in [s] (ArduCopter's EKF: ~40 s)."""
PX4_PARAMETER_FILES = ("parameters.bson", "parameters_backup.bson")
"""PX4 SITL's saved parameters in its working directory, loaded at boot when present."""


def claim_instance(
    kind: Kind,
    system_id: int,
    home: tuple[float, float, float],
    binary: Path,
    run_dir: Path,
    *,
    agent_port: int | None = None,
    avoid_ports: tuple[int, ...] = (),
    mocap: bool = False,
    imu_vibration: float | None = None,
) -> Instance:
    """An instance of ``kind`` on a number free now (held until :func:`start` hands it to the
    process); without ``agent_port`` the agent's link is the number's own free port (tests and
    scripts that start one instance)."""
    index, fd = claim(kind, avoid_ports=avoid_ports, default_agent=agent_port is None)
    port = default_agent_port(kind, index) if agent_port is None else agent_port
    return Instance(kind, index, system_id, home, binary, run_dir, port, mocap=mocap,
                    imu_vibration=imu_vibration, claim_fd=fd)  # fmt: skip


def start(inst: Instance) -> subprocess.Popen[bytes]:
    """Start ``inst`` in its own process group; its console goes to ``run_dir/console.log``. The
    process gets the instance number's lock; this process's copy is closed either way."""
    try:
        check_instance(inst)
        argv, env = command(inst)
        inst.run_dir.mkdir(parents=True, exist_ok=True)
        if inst.mocap and inst.kind == "ardupilot":
            (inst.run_dir / MOCAP_PARM).write_text(mocap_parm_text())
        if inst.kind == "ardupilot":
            _leave_stack_dumper(inst)
        if inst.kind == "px4":  # boot from the airframe's defaults, as ArduCopter's --wipe
            for name in PX4_PARAMETER_FILES:
                (inst.run_dir / name).unlink(missing_ok=True)
        with open(inst.run_dir / "console.log", "wb") as console:
            return subprocess.Popen(
                argv,
                cwd=inst.run_dir,
                env=env,
                stdin=subprocess.DEVNULL,
                stdout=console,
                stderr=subprocess.STDOUT,
                start_new_session=True,
                pass_fds=() if inst.claim_fd is None else (inst.claim_fd,),
            )
    finally:
        if inst.claim_fd is not None:
            os.close(inst.claim_fd)


def _leave_stack_dumper(inst: Instance) -> None:
    """ArduPilot SITL that dies of a signal (a floating point exception, a segfault) runs
    ``sh dumpstack.sh PID`` in its working directory: put the source tree's script (gdb, all
    threads) there, beside the binary's ``build/sitl/bin``, if it has one."""
    script = inst.binary.resolve().parents[3] / "Tools" / "scripts" / "dumpstack.sh"
    if script.is_file():
        shutil.copy(script, inst.run_dir / script.name)


def stop(proc: subprocess.Popen[bytes], timeout_s: float = 10.0) -> int:
    """SIGTERM then, after ``timeout_s``, SIGKILL to the process group ``proc`` leads (the
    instance and its children); returns its exit status."""
    if proc.poll() is None:
        _signal_group(proc, signal.SIGTERM)
        try:
            proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            _signal_group(proc, signal.SIGKILL)
            proc.wait(timeout=timeout_s)
    _signal_group(proc, signal.SIGKILL)  # children left behind by a leader that exited
    return int(proc.returncode)


def _signal_group(proc: subprocess.Popen[bytes], sig: int) -> None:
    with contextlib.suppress(ProcessLookupError):
        os.killpg(proc.pid, sig)


def show_instances(
    show_path: Path,
    run_dir: Path,
    binaries: dict[str, str | None],
    px4_imu_vibration: float | None = RESEARCH_AIRFRAME_VIBRATION,
) -> list[tuple[str, Instance]]:
    """(vehicle id, Instance) of every ``backend: mavlink`` vehicle of the show, each on a number
    claimed now; PX4 vehicles on mocap get ``px4_imu_vibration`` (None: SIH's own)."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
    from showfile import load_show

    show = load_show(show_path)
    vehicles = [v for v in show.vehicles if v.backend == "mavlink" and v.mavlink_url]
    if not vehicles:
        raise SitlError(f"{show_path}: no vehicle with backend: mavlink")
    ports = [url_kind_port(v.mavlink_url)[1] for v in vehicles]
    if len(set(ports)) < len(ports):
        raise SitlError(f"{show_path}: two vehicles share a mavlink_url port: {ports}")
    found = []
    for vehicle in vehicles:
        kind, port = url_kind_port(vehicle.mavlink_url)
        if vehicle.mavlink_system_id is None:
            raise SitlError(f"{show_path}: vehicle {vehicle.id} needs mavlink_system_id")
        if kind == "ardupilot" and not port_free("tcp", port):
            raise SitlError(f"{vehicle.id}: {vehicle.mavlink_url} is in use (another SITL?)")
        mocap = vehicle.mavlink_mocap != "none"
        vibration = px4_imu_vibration if kind == "px4" and mocap else None
        inst = claim_instance(kind, vehicle.mavlink_system_id, home_lla(vehicle.home_m_enu),
                              binary_for(kind, binaries[kind]), run_dir / vehicle.id,
                              agent_port=port, avoid_ports=tuple(ports), mocap=mocap,
                              imu_vibration=vibration)  # fmt: skip
        found.append((vehicle.id, inst))
    for _, inst in found:
        check_instance(inst)
    return found


def _vibration(text: str) -> float | None:
    if text == "stock":
        return None
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not 0.0 <= value <= 1.0:
        raise argparse.ArgumentTypeError(f"{text!r}: a number from 0 to 1, or stock")
    return value


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    parser.add_argument("show", type=Path, help="show file whose mavlink vehicles to start")
    parser.add_argument(
        "--run-dir",
        type=Path,
        default=None,
        help="instances' working dirs (default out/<show file name>-sitl)",
    )
    parser.add_argument("--arducopter", help=f"arducopter binary (${ENV_BINARY['ardupilot']})")
    parser.add_argument("--px4", help=f"px4 binary (${ENV_BINARY['px4']})")
    parser.add_argument("--ready-timeout", type=float, default=READY_TIMEOUT_S, metavar="S")
    parser.add_argument(
        "--px4-imu-vibration",
        type=_vibration,
        default=RESEARCH_AIRFRAME_VIBRATION,
        metavar="F|stock",
        help="PX4 SIH vehicles on mocap: armed IMU noise as a fraction of SIH's own, 0-1 "
        "(default 0: a research airframe; needs a px4 from build.py); stock: SIH's own",
    )
    return parser


STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
"""What stops the instances. SIGINT too, explicitly: a process started in the background of a
script (``start.py &``, ``nohup``, a test's or a benchmark's child of one) inherits SIGINT
ignored, and Python then sets no handler of its own: ``kill -INT`` left start.py and its SITL
instances running (tests/test_sitl_side_by_side.py, run from a background shell)."""


def _interrupt(_signum: int, _frame: object) -> None:
    STOP_REQUESTED.set()  # seen by the waits even where pymavlink swallows the exception
    raise KeyboardInterrupt


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    run_dir = args.run_dir or Path("out") / f"{args.show.stem}-sitl"
    procs: list[subprocess.Popen[bytes]] = []
    STOP_REQUESTED.clear()  # a main() run before in this process was stopped
    for signum in STOP_SIGNALS:
        signal.signal(signum, _interrupt)
    try:
        pairs = show_instances(
            args.show,
            run_dir.resolve(),
            {"ardupilot": args.arducopter, "px4": args.px4},
            args.px4_imu_vibration,
        )
        started_at = time.monotonic()
        for vehicle_id, inst in pairs:
            procs.append(start(inst))
            print(f"{vehicle_id}: {inst.kind} instance {inst.index}, system id {inst.system_id}, "
                  f"agent link {inst.url}, start.py's link {inst.probe_url}, pid {procs[-1].pid}, "
                  f"log {inst.run_dir / 'console.log'}", flush=True)  # fmt: skip
        for (vehicle_id, inst), proc in zip(pairs, procs, strict=True):
            seen = wait_ready(inst, proc, args.ready_timeout)
            print(f"{vehicle_id}: ready {time.monotonic() - started_at:.0f} s after start: "
                  f"{seen.summary()}", flush=True)  # fmt: skip
        print("all ready; Ctrl-C stops them", flush=True)
        while all(p.poll() is None for p in procs):
            time.sleep(0.5)
        print("an instance exited; stopping the others", file=sys.stderr)
        return 1
    except SitlError as exc:
        print(f"start.py: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 0
    finally:
        for proc in procs:
            stop(proc)
        if procs:
            print(f"stopped {len(procs)} instance(s)", file=sys.stderr)


if __name__ == "__main__":
    sys.exit(main())

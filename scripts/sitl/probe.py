"""Ask a MAVLink autopilot the questions a companion computer depends on; print its answers.

    .venv/bin/python scripts/sitl/probe.py ardupilot mavsim-ardupilot px4 mavsim-px4 \
        --out out/probe.json

Targets: ``ardupilot`` / ``px4`` start a real SITL instance (scripts/sitl/start.py, on a free
instance number, binaries from $SKYQUILL_ARDUCOPTER_SITL / $SKYQUILL_PX4_SITL, waiting until it
could arm);
``mavsim-ardupilot`` / ``mavsim-px4`` serve the project's simulated vehicle of that flavour on
udp 127.0.0.1:14690. Every case is a short exchange with bounded waits; the answer is a short
string. With several targets the answers are printed side by side, differences marked ``<>``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
import start as launch  # scripts/sitl/start.py, beside this file

SYSTEM_ID = 5
MAVSIM_PORT = 14690
ARDU_GUIDED, ARDU_LAND = 4, 9
PX4_OFFBOARD, PX4_AUTO, PX4_LAND_SUB = 6, 4, 6
RESULT = {
    0: "ACCEPTED",
    1: "TEMP_REJECTED",
    2: "DENIED",
    3: "UNSUPPORTED",
    4: "FAILED",
    5: "IN_PROGRESS",
    6: "CANCELLED",
    -1: "no ACK",
}
POSITION_ONLY = 0x09F8


class Probe:
    """A pymavlink link that keeps every message of the target's system, with a clock."""

    def __init__(self, flavor: str, url: str, system_id: int) -> None:
        from pymavlink import mavutil

        self.flavor = flavor
        self.conn = mavutil.mavlink_connection(url, source_system=255, source_component=191)
        self.sysid = system_id
        self.t0 = time.monotonic()
        self.log: list[tuple[float, Any]] = []
        self.stream: tuple[float, float, float] | None = None
        self.hold_ned = (0.0, 0.0, 0.0)
        self._beat = self._send = 0.0

    def now(self) -> float:
        return time.monotonic() - self.t0

    def pump(self, seconds: float, until: Callable[[Any], bool] | None = None) -> Any:
        """Read for ``seconds`` (heartbeat 1 Hz, setpoint stream 20 Hz when set); the first
        message for which ``until`` is true, else None."""
        end = self.now() + seconds
        while (t := self.now()) < end:
            if t >= self._beat:
                self._beat = t + 1.0
                self.conn.mav.heartbeat_send(6, 8, 0, 0, 4)
            if self.stream is not None and t >= self._send:
                self._send = t + 0.05
                self.conn.mav.set_position_target_local_ned_send(
                    int(t * 1000),
                    self.sysid,
                    1,
                    1,
                    POSITION_ONLY,
                    *self.stream,
                    0,
                    0,
                    0,
                    0,
                    0,
                    0,
                    0.0,
                    0.0,
                )
            msg = self.conn.recv_match(blocking=True, timeout=0.01)
            if msg is None or msg.get_srcSystem() != self.sysid:
                continue
            self.log.append((t, msg))
            if until is not None and until(msg):
                return msg
        return None

    def last(self, kind: str) -> Any:
        for _, msg in reversed(self.log):
            if msg.get_type() == kind:
                return msg
        return None

    def texts_since(self, t: float) -> list[str]:
        return [str(m.text) for s, m in self.log if s >= t and m.get_type() == "STATUSTEXT"]

    def command(self, cmd: int, *params: float) -> str:
        """COMMAND_LONG -> its result name (+ texts said meanwhile)."""
        t = self.now()
        p = [*params, 0, 0, 0, 0, 0, 0, 0][:7]
        ack = None
        for _ in range(2):
            self.conn.mav.command_long_send(self.sysid, 1, cmd, 0, *p)
            ack = self.pump(1.5, lambda m: m.get_type() == "COMMAND_ACK" and m.command == cmd)
            if ack is not None:
                break
        name = RESULT.get(-1 if ack is None else int(ack.result), str(ack and ack.result))
        texts = [x for x in self.texts_since(t) if "logger" not in x]
        return name + (f" {texts[:2]}" if texts else "")

    def set_mode(self, which: str) -> str:
        if self.flavor == "ardupilot":
            return self.command(176, 1, ARDU_GUIDED if which == "guided" else ARDU_LAND)
        if which == "guided":
            return self.command(176, 1, PX4_OFFBOARD, 0)
        return self.command(176, 1, PX4_AUTO, PX4_LAND_SUB)

    def mode(self) -> str:
        hb = self.last("HEARTBEAT")
        if hb is None:
            return "?"
        armed = "armed" if hb.base_mode & 128 else "disarmed"
        cm = int(hb.custom_mode)
        if self.flavor == "px4":
            return f"main {(cm >> 16) & 0xFF} sub {(cm >> 24) & 0xFF} {armed}"
        return f"mode {cm} {armed}"

    def position(self) -> tuple[float, float, float]:
        msg = self.last("LOCAL_POSITION_NED")
        return (0.0, 0.0, 0.0) if msg is None else (msg.x, msg.y, msg.z)

    def param(self, name: str, value: float | None, param_type: int = 9) -> str:
        t = self.now()
        if value is None:
            self.conn.mav.param_request_read_send(self.sysid, 1, name.encode(), -1)
        else:
            self.conn.mav.param_set_send(self.sysid, 1, name.encode(), value, param_type)
        reply = self.pump(3.0, lambda m: m.get_type() == "PARAM_VALUE" and m.param_id == name)
        texts = self.texts_since(t)
        if reply is None:
            return "no PARAM_VALUE" + (f" {texts[:2]}" if texts else "")
        return f"PARAM_VALUE {reply.param_value:g} type {reply.param_type}"


def case_basics(p: Probe) -> dict[str, str]:
    hb = p.pump(3.0, lambda m: m.get_type() == "HEARTBEAT")
    out = {
        "heartbeat": "none"
        if hb is None
        else f"type {hb.type} autopilot {hb.autopilot} base_mode {hb.base_mode:#x} "
        f"custom_mode {hb.custom_mode} status {hb.system_status}"
    }
    out["unknown command 31010"] = p.command(31010)
    out["SET_MESSAGE_INTERVAL 32 at 20 Hz"] = p.command(511, 32, 50000)
    t = p.now()
    p.pump(2.0)
    n = sum(1 for s, m in p.log if s >= t and m.get_type() == "LOCAL_POSITION_NED")
    out["LOCAL_POSITION_NED rate after it"] = f"{n / 2.0:.0f} Hz"
    p.command(511, 245, 200000)  # EXTENDED_SYS_STATE 5 Hz
    ess = p.pump(2.0, lambda m: m.get_type() == "EXTENDED_SYS_STATE")
    out["EXTENDED_SYS_STATE on the ground"] = (
        "none" if ess is None else f"landed {ess.landed_state}"
    )
    timeout_name = "GUID_TIMEOUT" if p.flavor == "ardupilot" else "COM_OF_LOSS_T"
    out[f"PARAM_SET {timeout_name}=1"] = p.param(timeout_name, 1.0)
    out["PARAM_REQUEST_READ unknown SKYQ_NOPE"] = p.param("SKYQ_NOPE", None)
    out["PARAM_SET unknown SKYQ_NOPE"] = p.param("SKYQ_NOPE", 1.0)
    out["SET_MODE guided/offboard, disarmed, no setpoints"] = p.set_mode("guided")
    out["mode after it"] = p.mode()
    return out


def case_flight(p: Probe) -> dict[str, str]:
    out: dict[str, str] = {}
    n, e, d = p.position()
    p.hold_ned = (n, e, d)
    out["setpoint while disarmed: moves?"] = _moved(p, (n + 1.0, e, d), 2.0)
    p.stream = (n, e, d)
    p.pump(1.2)
    out["SET_MODE guided/offboard with setpoints"] = p.set_mode("guided")
    out["ARM in guided/offboard"] = p.command(400, 1)
    if p.flavor == "ardupilot":
        p.stream = None
        out["NAV_TAKEOFF 2 m"] = p.command(22, 0, 0, 0, 0, 0, 0, 2.0)
    else:  # as the agent does: OFFBOARD climb by setpoints (NAV_TAKEOFF: see case_ground)
        p.stream = (n, e, d - 2.0)
    p.pump(10.0)
    out["height 10 s later"] = f"{-(p.position()[2] - d):.2f} m, {p.mode()}"
    ess = p.last("EXTENDED_SYS_STATE")
    out["EXTENDED_SYS_STATE in the air"] = "none" if ess is None else f"landed {ess.landed_state}"
    p.stream = None
    t = p.now()
    p.pump(4.0)
    moved = max(abs(a - b) for a, b in zip(p.position(), (n, e, d - 2.0), strict=True))
    out["setpoints stop 4 s (timeout 1 s)"] = (
        f"{p.mode()}, within {moved:.2f} m, texts {p.texts_since(t)[:2]}"
    )
    t = p.now()
    out["SET_MODE land"] = p.set_mode("land")
    disarmed = p.pump(30.0, lambda m: m.get_type() == "HEARTBEAT" and not m.base_mode & 128)
    out["land -> disarmed after"] = "not in 30 s" if disarmed is None else f"{p.now() - t:.0f} s"
    p.pump(1.5)
    out["mode reported after landing"] = p.mode()
    return out


def case_ground(p: Probe) -> dict[str, str]:
    out: dict[str, str] = {}
    n, e, d = p.position()
    p.stream = (n, e, d)
    p.pump(1.2)
    p.set_mode("guided")
    out["ARM again on the ground"] = p.command(400, 1)
    p.stream = None
    t = p.now()
    disarmed = p.pump(25.0, lambda m: m.get_type() == "HEARTBEAT" and not m.base_mode & 128)
    out["armed idle on ground -> auto disarm after"] = (
        "not in 25 s" if disarmed is None else f"{p.now() - t:.0f} s"
    )
    p.stream = (n, e, d)
    p.pump(1.2)
    out["SET_MODE guided/offboard again (stream on)"] = p.set_mode("guided")
    out["ARM after auto disarm"] = p.command(400, 1)
    out["force disarm (21196) on ground"] = p.command(400, 0, 21196)
    p.pump(1.2)
    p.set_mode("guided")
    p.command(400, 1)
    out["NAV_TAKEOFF param7=2 in guided/offboard, armed"] = p.command(22, 0, 0, 0, 0, 0, 0, 2.0)
    p.stream = (n, e, d - 2.0)
    p.pump(6.0)
    out["  + setpoints to 2 m at once: 6 s later"] = (
        f"height {-(p.position()[2] - d):.2f} m, "
        f"{p.mode()}, texts {[x for x in p.texts_since(p.now() - 6.0) if 'logger' not in x][:2]}"
    )
    p.stream = None
    p.command(400, 0, 21196)
    return out


def _moved(p: Probe, target: tuple[float, float, float], seconds: float) -> str:
    start = p.position()
    p.stream = target
    p.pump(seconds)
    p.stream = None
    moved = max(abs(a - b) for a, b in zip(p.position(), start, strict=True))
    return f"moved {moved:.2f} m, {p.mode()}"


def run_target(name: str) -> dict[str, str]:
    flavor = name.removeprefix("mavsim-")
    if name.startswith("mavsim-"):
        from mavsim.config import VehicleConfig
        from mavsim.server import MavsimServer

        config = VehicleConfig(vehicle_id="probe", system_id=1, port=MAVSIM_PORT, autopilot=flavor)  # type: ignore[arg-type]
        with MavsimServer([config]):
            time.sleep(4.0)  # position source delay 3 s
            return _cases(Probe(flavor, f"udpout:127.0.0.1:{MAVSIM_PORT}", 1))
    inst = launch.claim_instance(
        launch.as_kind(flavor),
        SYSTEM_ID,
        launch.home_lla((0.0, 0.0, 0.0)),
        launch.binary_for(launch.as_kind(flavor)),
        Path("out/sitl-probe") / flavor,
    )
    proc = launch.start(inst)
    try:
        launch.wait_ready(inst, proc, launch.READY_TIMEOUT_S)
        return _cases(Probe(flavor, inst.url, inst.system_id))
    finally:
        launch.stop(proc)


def _cases(p: Probe) -> dict[str, str]:
    answers = case_basics(p)
    answers.update(case_flight(p))
    answers.update(case_ground(p))
    return answers


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "targets", nargs="+", choices=("ardupilot", "px4", "mavsim-ardupilot", "mavsim-px4")
    )
    parser.add_argument("--out", type=Path, help="write the answers as JSON here")
    args = parser.parse_args()
    results: dict[str, dict[str, str]] = {}
    for target in args.targets:
        try:
            results[target] = run_target(target)
        except launch.SitlError as exc:
            print(f"probe.py: {target}: {exc}", file=sys.stderr)
            return 2
        if args.out is not None:
            args.out.parent.mkdir(parents=True, exist_ok=True)
            args.out.write_text(json.dumps(results, indent=1, ensure_ascii=False), "utf-8")
    cases = list(next(iter(results.values())))
    for case in cases:
        answers = [results[t].get(case, "-") for t in args.targets]
        mark = "<>" if len(set(answers)) > 1 else "=="
        print(
            f"{mark} {case}:\n"
            + "".join(f"     {t}: {a}\n" for t, a in zip(args.targets, answers, strict=True))
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())

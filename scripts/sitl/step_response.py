"""Measure a real autopilot's position response to a step setpoint (SITL), from its telemetry.

    .venv/bin/python scripts/sitl/step_response.py ardupilot --out out/step-ardupilot.json

Starts one SITL instance (scripts/sitl/start.py, on a free instance number, binary from
$SKYQUILL_ARDUCOPTER_SITL or $SKYQUILL_PX4_SITL), climbs to ``--height`` (ArduCopter: GUIDED,
arm, NAV_TAKEOFF; PX4: OFFBOARD with a position stream, arm), holds, then steps the position-only
SET_POSITION_TARGET_LOCAL_NED by ``--step`` metres north, later by ``--step-up`` metres up, at
50 Hz, logging LOCAL_POSITION_NED at 50 Hz. For each step it reports the dead time (5 % of the
step), the 10/50/90 % times, the overshoot, the 5 % settling time, the steady-state gain
(mean of the last second over the step) and a first-order-plus-dead-time fit (gain K, time
constant T, delay L). Raw samples and figures go to ``--out`` (JSON).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import least_squares

sys.path.insert(0, str(Path(__file__).resolve().parent))
import start as launch  # scripts/sitl/start.py, beside this file

SYSTEM_ID = 6
MAVSIM_PORT = 14691
RATE_HZ = 50.0
POSITION_ONLY = 0x09F8  # ignore velocity, acceleration, yaw rate; keep position and yaw
PX4_OFFBOARD = 6 << 16


class Flight:
    """One pymavlink link to the vehicle, logging LOCAL_POSITION_NED as (t [s], n, e, d)."""

    def __init__(self, url: str, system_id: int) -> None:
        from pymavlink import mavutil

        self.conn = mavutil.mavlink_connection(url, source_system=255, source_component=191)
        self.sysid = system_id
        self.t0 = time.monotonic()
        self.samples: list[tuple[float, float, float, float]] = []
        self.texts: list[str] = []
        self.acks: dict[int, int] = {}

    def now(self) -> float:
        return time.monotonic() - self.t0

    def pump(self, duration_s: float, target_ned: tuple[float, float, float] | None) -> None:
        """Read messages for ``duration_s``, streaming ``target_ned`` at 50 Hz when given."""
        end, next_send, next_beat = self.now() + duration_s, 0.0, 0.0
        while (t := self.now()) < end:
            if t >= next_beat:
                next_beat = t + 1.0
                self.conn.mav.heartbeat_send(6, 8, 0, 0, 4)
            if target_ned is not None and t >= next_send:
                next_send = t + 1.0 / RATE_HZ
                self.conn.mav.set_position_target_local_ned_send(
                    int(t * 1000),
                    self.sysid,
                    1,
                    1,
                    POSITION_ONLY,
                    *target_ned,
                    0,
                    0,
                    0,
                    0,
                    0,
                    0,
                    0.0,
                    0.0,
                )
            msg = self.conn.recv_match(blocking=True, timeout=0.005)
            if msg is None or msg.get_srcSystem() != self.sysid:
                continue
            kind = msg.get_type()
            if kind == "LOCAL_POSITION_NED":
                self.samples.append((self.now(), msg.x, msg.y, msg.z))
            elif kind == "STATUSTEXT":
                self.texts.append(str(msg.text))
            elif kind == "COMMAND_ACK":
                self.acks[int(msg.command)] = int(msg.result)

    def command(self, cmd: int, *params: float, stream: tuple[float, float, float] | None) -> int:
        """COMMAND_LONG; its MAV_RESULT (-1: no answer in 3 s)."""
        self.acks.pop(cmd, None)
        p = [*params, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0][:7]
        for _ in range(3):
            self.conn.mav.command_long_send(self.sysid, 1, cmd, 0, *p)
            self.pump(1.0, stream)
            if cmd in self.acks:
                return self.acks[cmd]
        return -1

    def position(self) -> tuple[float, float, float]:
        return self.samples[-1][1:] if self.samples else (0.0, 0.0, 0.0)


def take_off(f: Flight, kind: str, height_m: float) -> tuple[float, float, float]:
    """Airborne and settled at ``height_m``; the hover point (LOCAL_NED)."""
    f.command(511, 32, 1e6 / RATE_HZ, stream=None)  # LOCAL_POSITION_NED at 50 Hz
    f.pump(1.0, None)
    n, e, d = f.position()
    hover = (n, e, d - height_m)
    if kind.removeprefix("mavsim-") == "ardupilot":
        steps = [(176, (1, 4)), (400, (1,)), (22, (0, 0, 0, 0, 0, 0, height_m))]
        stream = None
    else:
        f.pump(1.5, (n, e, d))  # PX4: a live stream before OFFBOARD
        steps = [(176, (1, 6, 0)), (400, (1,))]
        stream = hover
    for cmd, params in steps:
        result = f.command(cmd, *params, stream=stream if cmd != 176 else (n, e, d))
        if result != 0:
            raise launch.SitlError(f"command {cmd} -> result {result}; texts {f.texts[-5:]}")
    f.pump(10.0, stream)  # ArduCopter: no setpoints during NAV_TAKEOFF's climb
    f.pump(4.0, hover)
    if f.position()[2] > d - 0.5 * height_m:
        raise launch.SitlError(f"no take-off: at {f.position()}; texts {f.texts[-5:]}")
    return hover


def analyse(t: np.ndarray, y: np.ndarray, t_step: float, step_m: float) -> dict[str, Any]:
    """Step metrics of ``y`` (the moved axis, relative to its value before the step)."""
    after = t >= t_step
    tt, r = t[after] - t_step, y[after] / step_m

    def first(level: float) -> float:
        idx = np.flatnonzero(r >= level)
        return float(tt[idx[0]]) if idx.size else float("nan")

    final = float(np.mean(r[tt >= tt[-1] - 1.0]))
    outside = np.flatnonzero(np.abs(r - final) > 0.05)
    settle = float(tt[outside[-1] + 1]) if outside.size and outside[-1] + 1 < tt.size else 0.0

    def fopdt(p: np.ndarray) -> np.ndarray:
        k, tau, delay = p
        model: np.ndarray = k * (1.0 - np.exp(-np.clip(tt - delay, 0.0, None) / tau))
        return model - r

    fit = least_squares(fopdt, x0=[1.0, 1.0, 0.1], bounds=([0.1, 0.01, 0.0], [3.0, 20.0, 3.0]))
    return {
        "step_m": step_m,
        "dead_time_s": first(0.05),
        "t10_s": first(0.1),
        "t50_s": first(0.5),
        "t90_s": first(0.9),
        "overshoot_pct": 100.0 * (float(np.max(r)) - final) / final,
        "settle_5pct_s": settle,
        "gain": final,
        "fopdt": {
            "K": fit.x[0],
            "T_s": fit.x[1],
            "L_s": fit.x[2],
            "rms_residual": float(np.sqrt(np.mean(fit.fun**2))),
        },
    }


def run(kind: str, args: argparse.Namespace) -> dict[str, Any]:
    if kind.startswith("mavsim-"):  # the project's simulated vehicle, for comparison
        sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
        from mavsim.config import VehicleConfig
        from mavsim.server import MavsimServer

        flavor = kind.removeprefix("mavsim-")
        config = VehicleConfig(vehicle_id="step", system_id=1, port=MAVSIM_PORT, autopilot=flavor)  # type: ignore[arg-type]
        with MavsimServer([config]):
            time.sleep(4.0)  # its position source delay
            return fly_steps(Flight(f"udpout:127.0.0.1:{MAVSIM_PORT}", 1), flavor, 0.0, args)
    inst = launch.claim_instance(
        launch.as_kind(kind),
        SYSTEM_ID,
        launch.home_lla((0.0, 0.0, 0.0)),
        launch.binary_for(launch.as_kind(kind)),
        args.run_dir / f"{kind}-step",
    )
    proc = launch.start(inst)
    try:
        ready_s = launch.wait_ready(inst, proc, launch.READY_TIMEOUT_S).waited_s
        return fly_steps(Flight(inst.url, inst.system_id), kind, ready_s, args)
    finally:
        launch.stop(proc)


def fly_steps(f: Flight, kind: str, ready_s: float, args: argparse.Namespace) -> dict[str, Any]:
    """Take off, then the north step and the up step; their metrics and samples."""
    hover = take_off(f, kind, args.height)
    results: dict[str, Any] = {"kind": kind, "ready_s": ready_s}
    for name, axis, delta in (("north", 0, args.step), ("up", 2, -args.step_up)):
        base = np.array(f.position())
        target = list(hover)
        target[axis] = base[axis] + delta
        start_index, t_step = len(f.samples), f.now()
        f.pump(args.hold, tuple(target))  # type: ignore[arg-type]
        data = np.array(f.samples[start_index - 50 :])
        t, y = data[:, 0], data[:, 1 + axis] - base[axis]
        results[name] = analyse(t, y, t_step, delta)
        results[name]["samples"] = {
            "t_s": (t - t_step).round(4).tolist(),
            "moved_m": y.round(4).tolist(),
        }
        hover = tuple(target)  # type: ignore[assignment]
    return results


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("kind", choices=("ardupilot", "px4", "mavsim-ardupilot", "mavsim-px4"))
    parser.add_argument("--height", type=float, default=2.0, help="hover height [m] (2)")
    parser.add_argument("--step", type=float, default=1.0, help="north step [m] (1)")
    parser.add_argument("--step-up", type=float, default=0.5, help="up step [m] (0.5)")
    parser.add_argument("--hold", type=float, default=8.0, help="time after each step [s] (8)")
    parser.add_argument("--run-dir", type=Path, default=Path("out/sitl-step"))
    parser.add_argument("--out", type=Path, help="write results (with samples) as JSON here")
    args = parser.parse_args()
    try:
        results = run(args.kind, args)
    except launch.SitlError as exc:
        print(f"step_response.py: {exc}", file=sys.stderr)
        return 2
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(results, indent=1), encoding="utf-8")
    for name in ("north", "up"):
        summary = {k: v for k, v in results[name].items() if k != "samples"}
        print(f"{args.kind} step {name}: {json.dumps(summary)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

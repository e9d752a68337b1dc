"""MAVLink numbers: writing quality per autopilot, setpoint rate and latency per vehicle.

    .venv/bin/python benchmarks/bench_mavlink.py [--vehicles 4] [--seconds 10] [--rates 50 100]
        [--writing 一 永] [--targets sim mavsim ardupilot px4]

Writing (first): the agent's job code writes each ``--writing`` character once per target
(benchmarks/mavlink_writing.py): the in-process simulator, mavsim, and ArduCopter / PX4 SITL when
$SKYQUILL_ARDUCOPTER_SITL / $SKYQUILL_PX4_SITL name their binaries (real time, about a minute
each, plus the autopilot's start); pen-down RMSE and ink IoU (2 cm brush) side by side, with the
lead the backend identified. ``--writing`` with no character skips it.

The vehicles (``mavsim``: simulated ArduCopters, real time) run in a child process, as
``skyquill sim-mavlink`` would; this process flies N MavlinkBackends on one asyncio loop at the
100 Hz control rate (harsher than a show, where each agent has its own process), streaming
SET_POSITION_TARGET_LOCAL_NED (p, v, a) along a circle at each requested rate, with
LOCAL_POSITION_NED asked at 100 Hz. The agent clock is the tick schedule on ``time.monotonic()``,
so setpoint stamps (``time_boot_ms``, whole ms) compare across the two processes:

- setpoint -> vehicle: the vehicle records ``monotonic - stamp`` when a setpoint arrives (the
  agent loop's lateness, UDP, the vehicle's select loop) and when its control loop takes it up
  (plus the wait for its next 100 Hz step, which depends on the phase of the two loops);
- round trip: the vehicle echoes the stamp of the setpoint it tracks in POSITION_TARGET_LOCAL_NED
  (50 Hz); the backend's process measures ``monotonic - stamp`` when the echo arrives.
"""

from __future__ import annotations

import argparse
import asyncio
import math
import multiprocessing
import statistics
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import mavlink_writing  # noqa: E402  (beside this file)

from mavsim.config import VehicleConfig  # noqa: E402
from mavsim.server import MavsimServer  # noqa: E402
from vehicle_agent.backends.base import Setpoint  # noqa: E402
from vehicle_agent.backends.mavlink.backend import MavlinkBackend  # noqa: E402
from vehicle_agent.backends.mavlink.settings import MavlinkSettings  # noqa: E402

CONTROL_HZ = 100.0
RADIUS_M = 0.3
PERIOD_S = 6.0
HOVER_Z_M = 1.0
WARM_UP_S = 2.0
"""The circle starts at full speed from rest: tracking is measured after this transient."""


def _vehicles(conn: Any, count: int) -> None:
    """Child process: serve ``count`` vehicles until told to stop, then report their stats."""
    configs = []
    for i in range(count):
        home = (2.0 * i, 0.0, 0.0)
        configs.append(VehicleConfig(vehicle_id=f"v{i}", system_id=i + 1, port=0, home_m_enu=home,
                                     position_source_delay_s=0.0))  # fmt: skip
    server = MavsimServer(configs).start()
    conn.send([ep.url for ep in server.endpoints])
    conn.recv()  # "reset": the stream starts now
    for ep in server.endpoints:
        ep.received_stamp_age_ms.clear()
        ep.applied_stamp_age_ms.clear()
        ep.autopilot.setpoints_received = 0
    conn.recv()  # "stop"
    stats = [
        {
            "received": ep.autopilot.setpoints_received,
            "arrived_ms": list(ep.received_stamp_age_ms),
            "applied_ms": list(ep.applied_stamp_age_ms),
        }
        for ep in server.endpoints
    ]
    server.stop()
    conn.send(stats)


def circle(i: int, t: float) -> Setpoint:
    w = 2 * math.pi / PERIOD_S
    c, s = math.cos(w * t), math.sin(w * t)
    r = RADIUS_M
    return Setpoint(
        position_m_enu=(2.0 * i + r * c, r * s, HOVER_Z_M),
        velocity_mps_enu=(-r * w * s, r * w * c, 0.0),
        acceleration_mps2_enu=(-r * w * w * c, -r * w * w * s, 0.0),
    )


async def _fly(urls: list[str], rate_hz: float, seconds: float, conn: Any) -> dict[str, Any]:
    """Fly one backend a vehicle along the circles for ``seconds`` (setpoints at ``rate_hz``)
    after hovering at their start; ``conn`` tells the vehicles' process when the measured stream
    starts and stops."""
    backends = [await _started_backend(url, i, rate_hz) for i, url in enumerate(urls)]
    round_trips: list[float] = []
    for backend in backends:
        _record_round_trips(backend, round_trips)
    await _hover_at_circle_start(backends)
    conn.send("reset")
    round_trips.clear()
    sent0 = [b.setpoints_sent for b in backends]
    stream = await _stream_circles(backends, seconds)
    conn.send("stop")
    faults = [b.fault for b in backends if b.fault]
    for backend in backends:
        await backend.close()
    return {
        "sent_hz": [
            (b.setpoints_sent - s0) / stream.elapsed_s
            for b, s0 in zip(backends, sent0, strict=True)
        ],
        "elapsed": stream.elapsed_s,
        "round_trip_ms": round_trips,
        "tracking_m": stream.tracking_m,
        "lateness_ms": stream.lateness_ms,
        "faults": faults,
    }


async def _started_backend(url: str, i: int, rate_hz: float) -> MavlinkBackend:
    """The started backend of vehicle ``i`` (origin 2 i m east) streaming at ``rate_hz``."""
    settings = MavlinkSettings(
        url=url,
        origin_m_enu=(2.0 * i, 0.0, 0.0),
        setpoint_rate_hz=rate_hz,
        control_rate_hz=CONTROL_HZ,
        telemetry_rate_hz=CONTROL_HZ,
    )
    backend = MavlinkBackend(settings)
    await backend.start()
    return backend


def _record_round_trips(backend: MavlinkBackend, round_trips: list[float]) -> None:
    """Append to ``round_trips`` the age in [ms] of each setpoint stamp the vehicle echoes in
    POSITION_TARGET_LOCAL_NED, after the link's own handling of the message."""
    link = backend.link
    handler = link.on_message

    def on_message(message: Any) -> None:
        handler(message)
        if message.get_type() == "POSITION_TARGET_LOCAL_NED":
            now_ms = int(time.monotonic() * 1000) & 0xFFFFFFFF
            round_trips.append(float((now_ms - message.time_boot_ms) & 0xFFFFFFFF))

    link.on_message = on_message


async def _hover_at_circle_start(backends: list[MavlinkBackend]) -> None:
    """Take off, wait (at most 15 s) until every vehicle holds, then settle 2 s on the start
    point of its circle."""
    dt = 1.0 / CONTROL_HZ
    for i, backend in enumerate(backends):
        await backend.takeoff(circle(i, 0.0).position_m_enu)
    t_hold = time.monotonic() + 15.0
    while not all(b.mode == "hold" for b in backends):
        for backend in backends:
            await backend.tick(None, time.monotonic())
        await asyncio.sleep(dt)
        if time.monotonic() > t_hold:
            raise SystemExit("vehicles did not reach hover")
    for _ in range(200):  # settle on the circle's start point
        for i, backend in enumerate(backends):
            await backend.tick(circle(i, 0.0), time.monotonic())
        await asyncio.sleep(dt)


@dataclass(frozen=True)
class _Stream:
    """What the agent side measured while streaming the circles."""

    elapsed_s: float
    """Wall-clock length of the stream in [s]."""
    tracking_m: list[float]
    """Distances in [m] of telemetry from the reference after the warm-up, all vehicles."""
    lateness_ms: list[float]
    """Lateness in [ms] of each control tick behind its schedule."""


async def _stream_circles(backends: list[MavlinkBackend], seconds: float) -> _Stream:
    """Tick every backend along its circle at the control rate for ``seconds``."""
    dt = 1.0 / CONTROL_HZ
    errors: list[float] = []
    lateness: list[float] = []
    t0 = time.monotonic()
    k = 0
    while time.monotonic() - t0 < seconds:
        now = t0 + k * dt  # the agent's clock: tick times, as TickClock gives them
        lateness.append((time.monotonic() - now) * 1000)
        for i, backend in enumerate(backends):
            snapshot = await backend.tick(circle(i, now - t0), now)
            if now - t0 > WARM_UP_S:
                reference = circle(i, now - t0).position_m_enu
                errors.append(math.dist(snapshot.position_m_enu, reference))
        k += 1
        await asyncio.sleep(max(0.0, t0 + k * dt - time.monotonic()))
    return _Stream(time.monotonic() - t0, errors, lateness)


def _pct(values: list[float], q: int) -> float:
    return statistics.quantiles(values, n=100)[q - 1] if len(values) > 2 else float("nan")


def run(vehicles: int, seconds: float, rate_hz: float) -> None:
    ctx = multiprocessing.get_context("spawn")
    parent, child = ctx.Pipe()
    process = ctx.Process(target=_vehicles, args=(child, vehicles), daemon=True)
    process.start()
    urls = parent.recv()
    result = asyncio.run(_fly(urls, rate_hz, seconds, parent))
    stats = parent.recv()
    process.join(timeout=10)
    received = [s["received"] / result["elapsed"] for s in stats]
    arrived = [a for s in stats for a in s["arrived_ms"]]
    applied = [a for s in stats for a in s["applied_ms"]]
    rtt = result["round_trip_ms"]
    print(f"\n{vehicles} vehicles, setpoints at {rate_hz:.0f} Hz, {seconds:.0f} s, "
          f"control loop {CONTROL_HZ:.0f} Hz")  # fmt: skip
    print("  sent per vehicle [Hz]:     " + " ".join(f"{r:6.1f}" for r in result["sent_hz"]))
    print("  received per vehicle [Hz]: " + " ".join(f"{r:6.1f}" for r in received))
    for name, ages in (("arrives at the vehicle", arrived), ("used by its loop", applied)):
        median, p95, p99 = statistics.median(ages), _pct(ages, 95), _pct(ages, 99)
        print(f"  setpoint {name} [ms]: median {median:.1f}  p95 {p95:.1f}  p99 {p99:.1f}  "
              f"max {max(ages):.1f}")  # fmt: skip
    print(f"  round trip via POSITION_TARGET echo [ms]: median {statistics.median(rtt):.1f}  "
          f"p95 {_pct(rtt, 95):.1f}  max {max(rtt):.1f}")  # fmt: skip
    late = result["lateness_ms"]
    print(f"  agent loop lateness [ms]: median {statistics.median(late):.2f}  "
          f"p99 {_pct(late, 99):.2f}")  # fmt: skip
    err = result["tracking_m"]
    print(f"  tracking after {WARM_UP_S:.0f} s (telemetry vs reference) [mm]: rms "
          f"{1000 * math.sqrt(statistics.fmean(e * e for e in err)):.1f}  max {1000 * max(err):.1f}"
          f"  faults: {result['faults'] or 'none'}")  # fmt: skip


def writing(texts: list[str], targets: list[str]) -> None:
    """Per target and character: the pace chosen, the error predicted for it and the error
    flown, the ink IoU and the lead the backend applied (each target identifies its tracking
    anew: its first character at the cautious first pace, the others at the identified one)."""
    print("\nwriting, 2 cm brush, planning.pace: tracking (aim 6 mm):")
    print(f"  {'target':<10}{'char':>5}{'stretch':>9}{'predicted':>11}{'flown':>8}"
          f"{'IoU':>7}{'lead':>8}   [mm, s]")  # fmt: skip
    for target in targets:
        if target in SITL_TARGETS and not mavlink_writing.sitl_available(target):
            print(
                f"  {target:<10} no SITL binary (${mavlink_writing.launcher().ENV_BINARY[target]})"
            )
            continue
        try:
            flown = mavlink_writing.write(target, texts)
        except (RuntimeError, OSError, mavlink_writing.launcher().SitlError) as exc:
            print(f"  {target:<10} failed: {exc}")
            continue
        for text, w in zip(texts, flown, strict=True):
            print("  " + _writing_row(target, text, w))
        _print_medians(target, flown)


SITL_TARGETS = ("ardupilot", "px4")


def _writing_row(target: str, text: str, w: Any) -> str:
    m = w.metrics
    predicted = m.extra.get("pace_predicted_rmse_pen_down_m")
    cells = (
        f"{m.extra.get('pace_stretch', 1.0):9.2f}",
        "      first" if predicted is None else f"{1000 * predicted:11.1f}",
        f"{1000 * m.rmse_pen_down_m:8.1f}",
        "      -" if m.iou is None else f"{m.iou:7.2f}",
        "       -" if w.lead_s is None else f"{w.lead_s:8.3f}",
    )
    return f"{target:<10}{text:>4} " + "".join(cells)


def _print_medians(target: str, flown: list[Any]) -> None:
    rmse = [1000 * w.metrics.rmse_pen_down_m for w in flown]
    ious = [w.metrics.iou for w in flown if w.metrics.iou is not None]
    predicted = "pace_predicted_rmse_pen_down_m"
    ratio = [w.metrics.rmse_pen_down_m / w.metrics.extra[predicted]
             for w in flown if predicted in w.metrics.extra]  # fmt: skip
    line = f"  {target:<10} median {statistics.median(rmse):.1f} mm"
    if ious:
        line += f", IoU median {statistics.median(ious):.2f} worst {min(ious):.2f}"
    if ratio:
        line += f", flown / predicted median {statistics.median(ratio):.2f}"
    print(line)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicles", type=int, default=4)
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--rates", type=float, nargs="+", default=[50.0, 100.0])
    parser.add_argument("--writing", nargs="*", default=["一"], metavar="CHAR")
    parser.add_argument("--targets", nargs="+", default=list(mavlink_writing.TARGETS),
                        choices=mavlink_writing.TARGETS)  # fmt: skip
    args = parser.parse_args()
    if args.seconds <= WARM_UP_S:
        parser.error(f"--seconds {args.seconds:g}: the tracking is measured after {WARM_UP_S:g} s, "
                     f"so a run must be longer")  # fmt: skip
    if args.writing:
        writing(args.writing, args.targets)
    for rate in args.rates:
        run(args.vehicles, args.seconds, rate)


if __name__ == "__main__":
    main()

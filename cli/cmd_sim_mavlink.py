"""``skyquill sim-mavlink SHOW.yaml``: the show's MAVLink vehicles simulated on their UDP ports."""

from __future__ import annotations

import argparse
import signal
import sys
import threading

NAME = "sim-mavlink"
HELP = "Serve the show's MAVLink vehicles as simulated ArduCopters or PX4s (one UDP endpoint each)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add = parser.add_argument
    add("show", help="show file; vehicles with backend: mavlink are simulated")
    add("--vehicle", action="append", metavar="ID", help="simulate only this vehicle (repeatable)")
    add(
        "--position-source-delay",
        type=float,
        default=3.0,
        metavar="S",
        help="seconds before the estimator has a position; arming is refused before (default 3)",
    )
    add(
        "--guided-timeout",
        type=float,
        default=3.0,
        metavar="S",
        help="GUID_TIMEOUT: the vehicle stops when setpoints stop this long (default 3)",
    )
    add(
        "--autopilot",
        choices=("ardupilot", "px4"),
        default="ardupilot",
        help="which autopilot the vehicles answer like (default ardupilot)",
    )
    add(
        "--param",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="a parameter's value at boot, e.g. GUID_OPTIONS=8 (repeatable; mavsim/params.py)",
    )
    add(
        "--refuse-arm",
        action="append",
        default=[],
        metavar="ID=REASON",
        help="always refuse to arm this vehicle, giving this pre-arm reason (repeatable)",
    )
    add(
        "--gains-eps",
        type=float,
        default=None,
        metavar="EPS",
        help="stiffness of the vehicles' position loop: the paper's poles divided by EPS "
        "(0.3: the stiff indoor tune; 1: the paper's own gains). Default: each autopilot's own "
        "response (ArduCopter's shaped target and PSC gains, PX4's MPC gains)",
    )
    add(
        "--time-scale",
        type=float,
        default=None,
        help="vehicle seconds per wall second (default: the show's time_scale, as its agents)",
    )


def run(args: argparse.Namespace) -> int:
    from mavsim.config import PositionGains
    from mavsim.errors import MavsimError
    from mavsim.server import MavsimServer
    from mavsim.show import vehicle_configs
    from showfile import ShowError, load_show

    try:
        show = load_show(args.show)
        gains = None if args.gains_eps is None else PositionGains.from_poles(args.gains_eps)
        refusals = dict(_pair(text) for text in args.refuse_arm)
        params = tuple((name, float(value)) for name, value in map(_param, args.param))
        configs = vehicle_configs(
            show,
            only=set(args.vehicle) if args.vehicle else None,
            gains=gains,
            arm_refusals=refusals,
            position_source_delay_s=args.position_source_delay,
            guided_timeout_s=args.guided_timeout,
            autopilot=args.autopilot,
            params=params,
        )
        if not configs:
            print(f"{args.show}: no vehicle with backend: mavlink", file=sys.stderr)
            return 2
        scale = args.time_scale if args.time_scale is not None else show.time_scale
        server = MavsimServer(configs, time_scale=scale)
    except (ShowError, MavsimError, ValueError) as exc:
        print(f"sim-mavlink: {exc}", file=sys.stderr)
        return 2
    for ep in server.endpoints:
        print(f"{ep.config.vehicle_id} {ep.url} system_id={ep.config.system_id}", flush=True)
    stop = threading.Event()
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: stop.set())
    try:
        server.run(stop)
    finally:
        server.close()
    return 0


def _param(text: str) -> tuple[str, str]:
    name, sep, value = text.partition("=")
    if not sep or not name:
        raise ValueError(f"--param {text!r}: expected NAME=VALUE")
    try:
        float(value)
    except ValueError:
        raise ValueError(f"--param {text!r}: {value!r} is not a number") from None
    return name, value


def _pair(text: str) -> tuple[str, str]:
    vehicle, sep, reason = text.partition("=")
    if not sep or not vehicle or not reason:
        raise ValueError(f"--refuse-arm {text!r}: expected ID=REASON")
    return vehicle, reason

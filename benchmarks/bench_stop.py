"""Clean stops: how long ``skyquill down`` takes for a show of many simulated vehicles, and how
many of its processes needed SIGKILL (the target: none).

    .venv/bin/python benchmarks/bench_stop.py [--vehicles 50] [--start-timeout 600]

A real ``skyquill up --headless`` of the Airshow show widened to ``--vehicles`` sim vehicles (a
board each, 2 m apart) is started; once every agent is on the bus (idle, as when a show ends),
``skyquill down`` stops it. The supervisor's own account (``up.log``: the slowest child's time
from SIGTERM to gone, who was SIGKILLed, and how many took longer than their grace but were let
finish as they were still busy stopping: the earlier supervisor killed those) is printed beside
the same for a one-vehicle show (the peer, measured in the same run). Heavy: 50 agents take
about 8 GB and both cores while they start; run it once, under ``nice``.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bus.keys import ShowKeys  # noqa: E402
from bus.pubsub import alive_keys  # noqa: E402
from bus.session import open_session  # noqa: E402
from cli.showrun import derived_show  # noqa: E402
from cli.supervisor import child_env, skyquill_argv  # noqa: E402
from showfile import Show, load_show  # noqa: E402
from trust.settings import ensure_show_keys, session_settings  # noqa: E402

AIRSHOW = ROOT / "shows" / "airshow-2014.yaml"
SPACING_M = 2.0


def wide_show(out: Path, count: int, source: Path = AIRSHOW) -> tuple[Path, Show]:
    """The show of ``source`` (the Airshow's) with ``count`` vehicles, each over its own board
    (a copy of its first), ``SPACING_M`` apart along x."""
    base = load_show(source)
    board0, vehicle0 = base.boards[0], base.vehicles[0]
    boards, vehicles = [], []
    for i in range(count):
        x_m = SPACING_M * i
        _, cy, cz = board0.center_m_enu
        _, hy, hz = vehicle0.home_m_enu
        boards.append(board0.model_copy(update={"id": f"b{i + 1}", "center_m_enu": (x_m, cy, cz)}))
        vehicles.append(
            vehicle0.model_copy(
                update={"id": f"uav{i + 1}", "board": f"b{i + 1}", "home_m_enu": (x_m, hy, hz)}
            )
        )
    return derived_show(source, out, boards=tuple(boards), vehicles=tuple(vehicles))


def wait_present(show: Show, timeout_s: float) -> float:
    """Seconds until every agent of ``show`` is on the bus (its liveliness token; the router
    answers that even while fifty agents starting keep the orchestrator too busy to)."""
    started = time.monotonic()
    keys = ShowKeys(show.show_id)
    wanted = {keys.vehicle_alive(v.id) for v in show.vehicles}
    settings = session_settings(show, "operator")
    with open_session(settings, role="client", open_timeout_s=timeout_s) as session:
        while time.monotonic() - started < timeout_s:
            if wanted <= alive_keys(session, keys.vehicles_alive_all, timeout_s=5.0):
                return time.monotonic() - started
            time.sleep(1.0)
    raise TimeoutError(f"not every vehicle present after {timeout_s:.0f} s")


def stop_once(count: int, start_timeout_s: float) -> None:
    """Start a ``count``-vehicle show with ``skyquill up``, stop it, print the account."""
    with tempfile.TemporaryDirectory() as tmp:
        path, show = wide_show(Path(tmp), count)
        ensure_show_keys(show)
        up = subprocess.Popen(
            skyquill_argv("up", str(path), "--headless", "--no-kiosk"),
            env=child_env(),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        try:
            ready_s = wait_present(show, start_timeout_s)
            time.sleep(2.0)  # idle, as a show between characters
        finally:
            started = time.monotonic()
            down = subprocess.run(
                skyquill_argv("down", str(path), "--timeout", "300"),
                env=child_env(),
                capture_output=True,
                text=True,
                timeout=320,
            )
            down_s = time.monotonic() - started
            if down.returncode != 0:
                up.terminate()  # it had not written its run file yet
            up.wait(timeout=320)
        log = (show.database_path.parent / "logs" / "up.log").read_text(encoding="utf-8")
    summary = [line for line in log.splitlines() if "stopped " in line and "SIGKILLed" in line]
    killed = [line for line in log.splitlines() if line.endswith("killing it")]
    print(
        f"{count:3d} vehicles: all present after {ready_s:.0f} s; `skyquill down` "
        f"{down_s:.1f} s wall (exit {down.returncode}); {len(killed)} SIGKILLed"
    )
    for line in summary:
        print(f"      up.log: {line.split(' ', 2)[-1]}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicles", type=int, default=50)
    parser.add_argument("--start-timeout", type=float, default=600.0)
    args = parser.parse_args()
    stop_once(1, args.start_timeout)  # the peer: one vehicle, same machine, same run
    stop_once(args.vehicles, args.start_timeout)


if __name__ == "__main__":
    main()

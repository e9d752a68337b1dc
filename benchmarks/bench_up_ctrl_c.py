"""Ctrl-C in ``skyquill up``: wall time from the SIGINT to the exit of ``up``, with nothing in the
air, and the supervisor's own account of the stop (``up.log``: how long its children took).

    .venv/bin/python benchmarks/bench_up_ctrl_c.py [--runs 3] [--vehicles 1] [--burners 0]
    .venv/bin/python benchmarks/bench_up_ctrl_c.py --peer [--burners 8]

A real ``skyquill up --headless --no-kiosk`` of the solo show (one brush quadrotor: router,
orchestrator, agent) widened to ``--vehicles`` sim vehicles is started; once every agent is on
the bus and idle, ``up`` gets SIGINT. Printed per run: the wall time to its exit, its exit status,
the lines it wrote to stderr after the signal, the stop's total from ``up.log``, and the 1-min
load beside them (figures under load are noisy: compare runs of one sitting). ``--peer``: the
same show's processes under a :class:`cli.supervisor.Supervisor` of this process, stopped group by
group and then (started again) all at once, alternately, in one sitting. ``--burners N``: N
busy processes at the children's priority for the few seconds of each stop, a loaded machine
(load 13.8 was measured at the first figure, issue 34). About 20 s a run; hold the shared lock
(``flock /tmp/heavy.lock``) for several.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench_stop import wait_present, wide_show  # noqa: E402

from cli.showrun import derived_show  # noqa: E402
from cli.supervisor import Supervisor, child_env, show_children, skyquill_argv  # noqa: E402
from showfile import load_show  # noqa: E402
from trust.settings import ensure_show_keys  # noqa: E402

SOLO = ROOT / "shows" / "solo.yaml"
IDLE_S = 2.0
"""Wall [s] the show runs idle between every agent on the bus and the Ctrl-C."""


def _show(out: Path, count: int) -> Path:
    """The solo show in ``out`` with ``count`` vehicles, each over its own board."""
    return derived_show(SOLO, out)[0] if count == 1 else wide_show(out, count, SOLO)[0]


@contextlib.contextmanager
def burning(count: int) -> Iterator[None]:
    """``count`` busy processes at this process's priority while within."""
    burners = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(count)]
    try:
        yield
    finally:
        for burner in burners:
            burner.kill()
            burner.wait()


def peer_once(count: int, burners: int, *, grounded: bool) -> float:
    """The show's processes under a supervisor here, stopped in order or together; [s]."""
    with tempfile.TemporaryDirectory() as tmp:
        path = _show(Path(tmp), count)
        show = load_show(path)
        ensure_show_keys(show)
        specs = show_children(path, [v.id for v in show.vehicles], log_dir=Path(tmp) / "logs")
        supervisor = Supervisor(specs, env=child_env(), say=lambda _line: None)
        supervisor.start()
        try:
            wait_present(show, 300.0)
            time.sleep(IDLE_S)
        finally:
            with burning(burners):
                load = os.getloadavg()[0]
                report = supervisor.stop(grounded=grounded)
    how = "together" if grounded else "in order"
    print(f"peer {how:8s} load {load:4.1f}: {report.summary()}")
    return report.total_s


def interrupt_once(count: int, burners: int) -> None:
    """Start the show with ``skyquill up``, Ctrl-C it once idle, print the figures."""
    with tempfile.TemporaryDirectory() as tmp:
        path = _show(Path(tmp), count)
        show = load_show(path)
        ensure_show_keys(show)
        up = subprocess.Popen(
            skyquill_argv("up", str(path), "--headless", "--no-kiosk"),
            env=child_env(),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
        try:
            wait_present(show, 300.0)
            time.sleep(IDLE_S)
            marker = (show.database_path.parent / "logs" / "up.log").stat().st_size
            with burning(burners):
                load = os.getloadavg()[0]
                sent_s = time.monotonic()
                up.send_signal(signal.SIGINT)
                _, stderr = up.communicate(timeout=120)
                took_s = time.monotonic() - sent_s
        finally:
            if up.poll() is None:
                up.kill()
                up.wait()
                subprocess.run(skyquill_argv("down", str(path)), env=child_env(), timeout=120)
        log = (show.database_path.parent / "logs" / "up.log").read_text(encoding="utf-8")
    after = log[marker:].splitlines()
    summary = next((line for line in after if "SIGKILLed" in line), "no summary in up.log")
    said = [line for line in stderr.splitlines() if line.strip()]
    tail = said[-3:]
    print(
        f"{count} vehicle(s), load {load:.1f}: exit {up.returncode} {took_s:.2f} s after SIGINT; "
        f"stderr's last lines {tail}\n    up.log: {summary.split(' ', 2)[-1]}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--vehicles", type=int, default=1)
    parser.add_argument("--burners", type=int, default=0)
    parser.add_argument("--peer", action="store_true")
    args = parser.parse_args()
    for _ in range(args.runs):
        if args.peer:
            ordered = peer_once(args.vehicles, args.burners, grounded=False)
            together = peer_once(args.vehicles, args.burners, grounded=True)
            print(f"    together / in order: {together / ordered:.2f}")
        else:
            interrupt_once(args.vehicles, args.burners)


if __name__ == "__main__":
    main()

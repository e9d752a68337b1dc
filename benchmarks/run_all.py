"""Run every benchmark in turn and print their numbers (``make bench``).

Each script pins itself to one core where the target says "on one core" and prints its peer
measured in the same run. ``--quick`` passes each script its smallest setting, for a smoke run.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).parent

FULL: dict[str, list[str]] = {
    "bench_planner.py": [],
    "bench_show.py": ["--eta"],
    "bench_sim.py": [],
    "bench_bus.py": [],
    "bench_fleet.py": [],
    "bench_mavlink.py": [],
    "bench_tui.py": [],
    "bench_cli.py": [],
    "bench_stop.py": [],
    "bench_ground.py": [],
    "bench_agent.py": ["--vehicles", "50"],
    "bench_fleet_host.py": ["--vehicles", "50,100,250", "--writing", "10"],
}
QUICK: dict[str, list[str]] = {
    "bench_planner.py": ["--quick"],
    "bench_show.py": ["--quick"],
    "bench_sim.py": ["--quick"],
    "bench_bus.py": ["--seconds", "2", "--submissions", "50"],
    "bench_fleet.py": ["--skip-show"],
    "bench_mavlink.py": ["--seconds", "3"],
    "bench_tui.py": ["--seconds", "2"],
    "bench_cli.py": ["--runs", "2"],
    "bench_stop.py": ["--vehicles", "4"],
    "bench_ground.py": ["--quick"],
    "bench_agent.py": ["--vehicles", "2", "--idle-s", "3"],
    "bench_fleet_host.py": ["--vehicles", "3", "--writing", "3", "--peer", "2", "--window-s", "3"],
}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="smallest setting of each script")
    parser.add_argument("only", nargs="*", help="script names to run (default: all)")
    args = parser.parse_args()
    plan = QUICK if args.quick else FULL
    failed: list[str] = []
    for script, script_args in plan.items():
        if args.only and script not in args.only and script.removesuffix(".py") not in args.only:
            continue
        print(f"\n===== {script} {' '.join(script_args)}", flush=True)
        start = time.perf_counter()
        status = subprocess.call([sys.executable, str(HERE / script), *script_args])
        elapsed_s = time.perf_counter() - start
        print(f"===== {script}: exit {status} after {elapsed_s:.1f} s", flush=True)
        if status != 0:
            failed.append(script)
    if failed:
        print(f"failed: {', '.join(failed)}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())

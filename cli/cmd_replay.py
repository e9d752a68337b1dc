"""``skyquill replay SHOW.yaml JOB``: one flown job as a Foxglove recording (``scene.replay``).

Reads the job's files (``<database dir>/jobs/<job>-<vehicle>-<attempt>/``: what was flown, the
reference and the plan, the metrics) and writes ``<job>-<vehicle>-<attempt>.mcap``: the vehicle
moving in the venue, the plan, the flown path and the ink, tracking error and force to plot.
Open it in Foxglove with ``docs/foxglove-layout.json``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

NAME = "replay"
HELP = "Write one flown job as a Foxglove recording (plan, flight, force, ink)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("show", type=Path, help="show file (YAML)")
    parser.add_argument("job", help="job id (as in skyquill status)")
    parser.add_argument("--attempt", type=int, help="which attempt (default: the last one kept)")
    parser.add_argument(
        "--out", type=Path, help="MCAP file to write (default: <job>-<vehicle>-<attempt>.mcap here)"
    )


def run(args: argparse.Namespace) -> int:
    from scene.replay import ReplayError, job_folders, replay_job
    from showfile import ShowError, load_show

    try:
        show = load_show(args.show)
        folders = job_folders(show, args.job)
    except (ShowError, ReplayError) as exc:
        print(f"skyquill replay: {exc}", file=sys.stderr)
        return 2
    chosen = [f for f in folders if args.attempt in (None, f.attempt)]
    if not chosen:
        kept = ", ".join(str(f.attempt) for f in folders)
        print(f"skyquill replay: job {args.job} has no attempt {args.attempt} (kept: {kept})",
              file=sys.stderr)  # fmt: skip
        return 2
    folder = chosen[-1]
    out = args.out or Path(f"{folder.job_id}-{folder.vehicle_id}-{folder.attempt}.mcap")
    flight = folder.path / "flight.npz"
    try:
        count = replay_job(show, folder, out, start_ns=flight.stat().st_mtime_ns)
    except (OSError, ValueError, KeyError) as exc:
        print(f"skyquill replay: {folder.path}: {exc}", file=sys.stderr)
        return 1
    print(
        f"job {folder.job_id} (attempt {folder.attempt} on {folder.vehicle_id}): {count} "
        f"messages written to {out}; open it in Foxglove with docs/foxglove-layout.json"
    )
    return 0

"""``skyquill demo``: the Airshow show, simulated, with a few characters; prints how they came out.

Runs a copy of ``shows/airshow-2014.yaml`` (four quadrotors) headless on a free loopback port with
its own storage under ``out/demo/<time>/``, submits the characters, lays a fresh sheet on each
board after its character as the Airshow's crew did, waits until every one is written, prints a
table (job, vehicle, RMSE, IoU, simulated flight time) and where the recording, the jobs' files
and logs are, then stops everything. Needs no configuration.
"""

from __future__ import annotations

import argparse
import sys
import time
import unicodedata
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from bus.messages import JobState

NAME = "demo"
HELP = "Run the simulated Airshow show with a few characters and print how well they were written."

DEFAULT_TEXTS = ("永", "光", "马", "A")
PICTURE_TIMEOUT_S = 30.0
"""How long in [s] to wait for the agents to draw the last jobs' report.png."""
SHOW = Path(__file__).resolve().parent.parent / "shows" / "airshow-2014.yaml"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "texts", nargs="*", help=f"characters to write (default: {' '.join(DEFAULT_TEXTS)})"
    )
    parser.add_argument("--show", type=Path, default=SHOW, help="show file (default: the Airshow)")
    parser.add_argument(
        "--time-scale",
        type=float,
        default=4.0,
        help="simulated seconds per wall second (default 4; a slow CPU simply runs slower)",
    )
    parser.add_argument("--out", type=Path, default=Path("out") / "demo", help="output directory")
    parser.add_argument("--timeout", type=float, default=600.0, help="give up after [s] (600)")


def run(args: argparse.Namespace) -> int:
    from cli.interrupt import hurry_on_ctrl_c
    from cli.showrun import ShowRun, Stagehand, derived_show, submit_texts, wait_for_jobs
    from showfile import ShowError

    if not args.time_scale > 0.0:
        print("skyquill demo: --time-scale must be positive", file=sys.stderr)
        return 2
    texts = list(args.texts) or list(DEFAULT_TEXTS)
    out_dir = args.out / time.strftime("%Y%m%d-%H%M%S")
    try:
        show_path, show = derived_show(args.show, out_dir, time_scale=args.time_scale)
    except ShowError as exc:
        print(f"skyquill demo: {exc}", file=sys.stderr)
        return 2
    print(
        f"show {show.show_id}: {len(show.vehicles)} vehicles, time scale {args.time_scale:g}, "
        f"Zenoh router on {show.zenoh.router_listen[0]}"
    )
    started = time.monotonic()
    with (
        ShowRun(show_path, show, log_dir=out_dir / "logs") as run_,
        hurry_on_ctrl_c(run_.supervisor),  # Ctrl-C: one line, stopped in a second or two
        run_.client() as session,
        Stagehand(session, run_.keys),  # the crew: a sheet after each character
    ):
        replies = submit_texts(session, run_.keys, texts)
        for text, reply in zip(texts, replies, strict=True):
            print(f"submitted {text!r}: job {reply.job_id}")
        job_ids = [str(reply.job_id) for reply in replies]
        progress = _Progress(texts)
        try:
            jobs = wait_for_jobs(
                session, run_.keys, job_ids, timeout_s=args.timeout, on_change=progress.show
            )
        except TimeoutError as exc:
            print(f"skyquill demo: {exc}; logs in {out_dir / 'logs'}", file=sys.stderr)
            return 1
        reports_dir = show.database_path.parent / "jobs"
        pictures = _wait_for_pictures(reports_dir, [j.job_id for j in jobs if j.state == "done"])
    print()
    print(_table(texts, jobs))
    print()
    print(
        f"{sum(j.state == 'done' for j in jobs)}/{len(jobs)} written in "
        f"{time.monotonic() - started:.0f} s of wall-clock time"
    )
    print(
        f"sim time: each flight's simulated duration (time scale {args.time_scale:g}: up to "
        f"{args.time_scale:g} simulated seconds per wall second)"
    )
    print(f"recording: {show.recordings_dir}/  (MCAP; read it with the mcap Python package)")
    print(f"reports:   {reports_dir}/  (per job: {job_files(reports_dir)})")
    for picture in pictures:
        print(f"  {picture}")
    print(f"database:  {show.database_path}")
    print(f"logs:      {out_dir / 'logs'}/")
    return 0 if all(j.state == "done" for j in jobs) else 1


def _wait_for_pictures(
    reports_dir: Path, job_ids: list[str], timeout_s: float = PICTURE_TIMEOUT_S
) -> list[Path]:
    """The ``report.png`` of each job, waiting a little for the agents still drawing them."""
    deadline = time.monotonic() + timeout_s
    while True:
        found = [sorted(reports_dir.glob(f"{job_id}-*/report.png")) for job_id in job_ids]
        if all(found) or time.monotonic() > deadline:
            return [path for paths in found for path in paths]
        time.sleep(0.2)


class _Progress:
    """One line whenever a job changes state."""

    def __init__(self, texts: list[str]) -> None:
        self._texts = texts
        self._seen: dict[str, str] = {}

    def show(self, jobs: list[JobState]) -> None:
        for job in jobs:
            key = f"{job.state}:{job.vehicle_id}"
            if self._seen.get(job.job_id) != key:
                self._seen[job.job_id] = key
                on = f" on {job.vehicle_id}" if job.vehicle_id else ""
                print(f"  {job.label!s:>6}  {job.job_id}  {job.state}{on}", flush=True)


def job_files(reports_dir: Path) -> str:
    """The files the jobs' directories hold (what was written, not what might be), in the
    order the agents write them."""
    order = ("metrics.json", "TRAJ.json", "flight.npz", "report.png")
    names = {p.name for p in reports_dir.glob("*/*") if p.is_file()}
    shown = [n for n in order if n in names] + sorted(names - set(order))
    return ", ".join(shown) or "none written"


def _table(texts: list[str], jobs: list[JobState]) -> str:
    """One row per job; a job not ``done`` claims no ink (IoU 0), its errors stay measured."""
    from cli.summary import length, ratio, seconds

    rows = [("text", "job", "vehicle", "state", "pen-down RMSE", "RMSE", "ink IoU", "sim time")]
    for text, job in zip(texts, jobs, strict=True):
        m = job.metrics
        iou = (m.iou if job.state == "done" else 0.0) if m else None
        rows.append(
            (
                text,
                job.job_id,
                job.vehicle_id or "-",
                job.state,
                length(m.rmse_pen_down_m) if m else "-",
                length(m.rmse_m) if m else "-",
                ratio(iou),
                seconds(m.duration_s) if m else "-",
            )
        )
    widths = [max(_width(str(row[i])) for row in rows) for i in range(len(rows[0]))]
    lines = [
        "  ".join(c + " " * (w - _width(c)) for c, w in zip(map(str, row), widths, strict=True))
        for row in rows
    ]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(line.rstrip() for line in lines)


def _width(text: str) -> int:
    """Terminal columns of ``text`` (CJK characters take two)."""
    return sum(2 if unicodedata.east_asian_width(c) in "WF" else 1 for c in text)

"""Memory of a whole show: every process's resident set, alone and together, from start to soak.

    python benchmarks/bench_memory.py                  # 10 minutes at time scale 4
    python benchmarks/bench_memory.py --minutes 3
    python benchmarks/bench_memory.py --fleet-hosts 1     # the vehicles in one fleet host
    python benchmarks/bench_memory.py --minutes 60 --png out/bench/memory.png

Runs ``shows/airshow-2014.yaml`` (router, orchestrator, four simulated agents and their planning
workers, real Zenoh on loopback) and keeps ``--waiting`` characters waiting. It samples every
process of the show (the supervisor's children and theirs, e.g. an agent's planning worker):

- RSS (``VmRSS``): what ``top`` shows per process; summed over processes it counts every shared
  page (libraries, the Zenoh shared-memory segments) once per process that maps it;
- PSS (``/proc/<pid>/smaps_rollup``): each shared page divided among the processes that map it,
  so the sum over the show is the memory the show holds in all its processes together;
- anonymous (``RssAnon``): the process's own heap, what a leak grows.

Printed: the table when every vehicle first reports ready (``ready``: are the workers there
already, warm?), at the end, the peak, and the least-squares slope of each after ``--warmup-s``
in MiB/hour, beside the slope of the run's second half (``late``: a process that keeps a bounded
history, like the orchestrator's latest finished jobs, grows until it is full and is flat after);
the totals the same way, then the totals of RSS and PSS against the target of 1 GiB (ratios) and
the machine's load over the run. ``--png`` draws the totals and the long-lived processes over
the run. A drawing process (a child of a planning
worker, ``vehicle_agent/picture_process.py``) is counted in ``all together`` while it runs, and
left out of ``long-lived``, whose slope is the one a leak shows in. ``bench_soak.py`` is the
long run (disk, pictures).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from bench_show import SHOW, wait_ready  # noqa: E402
from bench_soak import Jobs, children_of, keep_waiting  # noqa: E402

from bus.messages import JobState  # noqa: E402
from bus.pubsub import subscribe  # noqa: E402
from cli.showrun import ShowRun, Stagehand, derived_show  # noqa: E402

MIB = 1024.0 * 1024.0
MEASURES = ("rss", "pss", "anon")
TARGET_MIB = 1024.0
ALL = "all together"
LONG_LIVED = "long-lived"
"""The total without the drawing processes, which come and go with each batch of pictures."""
TOTALS = (LONG_LIVED, ALL)
TRANSIENT = ("picture", *(f"picture {k}" for k in range(2, 10)))
"""How the names of drawing processes end (``uav1 worker picture``)."""
"""Issue 35: a four-vehicle show holds at most 1 GiB in all its processes together."""


def memory_kib(pid: int) -> dict[str, int] | None:
    """RSS, PSS and anonymous resident memory of ``pid`` in KiB (None: it is gone)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
        rollup = Path(f"/proc/{pid}/smaps_rollup").read_text()
    except (FileNotFoundError, ProcessLookupError, PermissionError):
        return None
    found: dict[str, int] = {}
    for text, names in ((status, {"VmRSS": "rss", "RssAnon": "anon"}), (rollup, {"Pss": "pss"})):
        for line in text.splitlines():
            name, _, value = line.partition(":")
            if name in names:
                found[names[name]] = int(value.split()[0])
    return found if len(found) == len(MEASURES) else None


def show_processes(run: ShowRun) -> dict[str, int]:
    """Name -> pid of every running process of the show (an agent's worker under its name)."""
    found: dict[str, int] = {}
    for name in run.supervisor.names:
        pid = run.supervisor.pid(name)
        if pid is None:
            continue
        label = name.removeprefix("agent ")
        found[label] = pid
        for k, child in enumerate(children_of(pid)):
            worker = f"{label} worker" + (f" {k + 1}" if k else "")
            found[worker] = child
            for j, grandchild in enumerate(children_of(child)):  # a picture being drawn
                found[f"{worker} picture" + (f" {j + 1}" if j else "")] = grandchild
    return found


@dataclass
class Series:
    """Samples per process and measure: (seconds since ready, KiB)."""

    points: dict[tuple[str, str], list[tuple[float, int]]] = field(default_factory=dict)
    at_ready: dict[tuple[str, str], int] = field(default_factory=dict)
    load_1min: list[float] = field(default_factory=list)
    """The machine's 1-minute load average at each sample."""

    def take(self, t_s: float, run: ShowRun) -> None:
        self.load_1min.append(os.getloadavg()[0])
        totals = {total: dict.fromkeys(MEASURES, 0) for total in TOTALS}
        for name, pid in show_processes(run).items():
            sizes = memory_kib(pid)
            if sizes is None:
                continue
            for measure, kib in sizes.items():
                self.points.setdefault((name, measure), []).append((t_s, kib))
                totals[ALL][measure] += kib
                if not name.endswith(TRANSIENT):
                    totals[LONG_LIVED][measure] += kib
                if t_s == 0.0:
                    self.at_ready[(name, measure)] = kib
        for total, sums in totals.items():
            for measure, kib in sums.items():
                self.points.setdefault((total, measure), []).append((t_s, kib))
                if t_s == 0.0:
                    self.at_ready[(total, measure)] = kib


def slope_mib_per_h(points: list[tuple[float, int]], after_s: float) -> float | None:
    """Least-squares slope in MiB/hour of the points at or after ``after_s``."""
    kept = [(t, v) for t, v in points if t >= after_s]
    if len(kept) < 3:
        return None
    fit = statistics.linear_regression([t for t, _ in kept], [v for _, v in kept])
    return fit.slope * 3600.0 / 1024.0


def late_s(series: Series, warmup_s: float) -> float:
    """Where the run's second half starts, after the warm-up [s since ready]."""
    end_s = series.points[(ALL, "rss")][-1][0] if series.points else 0.0
    return (max(warmup_s, 0.0) + end_s) / 2.0


def report(series: Series, warmup_s: float) -> None:
    """One line per process: ready / end / peak / slope (after the warm-up, and in the second
    half) of RSS, PSS and anonymous memory."""
    names = list(dict.fromkeys(name for name, _ in series.points))
    names.sort(key=lambda n: n in TOTALS)
    half_s = late_s(series, warmup_s)
    heads = "".join(f" {m.upper():>5}: ready   end  peak   slope/h    late/h" for m in MEASURES)
    print(f"  {'process':20}{heads}")
    for name in names:
        cells = []
        for measure in MEASURES:
            points = series.points.get((name, measure), [])
            if not points:
                cells.append(f" {'':5}  {'-':>5} {'':5} {'':5} {'':9} {'':9}")
                continue
            ready = series.at_ready.get((name, measure))
            # a process that comes and goes has no trend: its samples are other processes
            gone = len(points) < len(series.load_1min)
            slopes = [None if gone else slope_mib_per_h(points, s) for s in (warmup_s, half_s)]
            cells.append(
                f" {'':5}  {'-' if ready is None else f'{ready / 1024:.0f}':>5}"
                f" {points[-1][1] / 1024:5.0f} {max(v for _, v in points) / 1024:5.0f}"
                + "".join(f" {'-' if s is None else f'{s:+7.1f}':>9}" for s in slopes)
            )
        print(f"  {name:20}" + "".join(cells))


def verdict(series: Series, warmup_s: float) -> None:
    """The show's RSS and PSS summed over its processes against :data:`TARGET_MIB`: at the end,
    at the peak, their mean after ``warmup_s`` and its slope, as ratios (no pass or fail)."""
    for total, measure in ((t, m) for m in ("rss", "pss") for t in TOTALS):
        points = series.points.get((total, measure), [])
        if not points:
            continue
        end_mib, peak_mib = points[-1][1] / 1024, max(v for _, v in points) / 1024
        kept = [v / 1024 for t, v in points if t >= warmup_s] or [end_mib]
        slope = slope_mib_per_h(points, warmup_s)
        late = slope_mib_per_h(points, late_s(series, warmup_s))
        print(
            f"  {measure.upper()} {total:12} against {TARGET_MIB:.0f} MiB: end {end_mib:.0f}"
            f" ({end_mib / TARGET_MIB:.2f}), peak {peak_mib:.0f} ({peak_mib / TARGET_MIB:.2f}),"
            f" mean after {warmup_s:.0f} s {statistics.fmean(kept):.0f}"
            f" ({statistics.fmean(kept) / TARGET_MIB:.2f}), slope"
            f" {'-' if slope is None else f'{slope:+.0f} MiB/h'}"
            f" (second half {'-' if late is None else f'{late:+.0f} MiB/h'})"
        )
    if series.load_1min:
        loads = series.load_1min
        print(
            f"  load (1 min) over the samples: min {min(loads):.1f},"
            f" mean {statistics.fmean(loads):.1f}, max {max(loads):.1f}"
        )


def figure(series: Series, path: Path) -> None:
    """RSS over the run: the totals, and each long-lived process (PSS total dashed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_total, ax_each) = plt.subplots(1, 2, figsize=(12.8, 4.8))
    for (name, measure), points in series.points.items():
        transient = len(points) < len(series.load_1min)  # drawing processes come and go
        if measure == "anon" or transient or (measure == "pss" and name not in TOTALS):
            continue
        minutes = [t / 60.0 for t, _ in points]
        mib = [v / 1024 for _, v in points]
        if name in TOTALS:
            ax_total.plot(
                minutes, mib, "--" if measure == "pss" else "-", label=f"{name} {measure}"
            )
        else:
            ax_each.plot(minutes, mib, label=name)
    ax_total.axhline(TARGET_MIB, color="red", linewidth=0.8, label="target 1 GiB")
    for ax, title in ((ax_total, "the show together"), (ax_each, "long-lived processes (RSS)")):
        ax.set(xlabel="minutes since every vehicle was ready", ylabel="MiB", title=title)
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    print(f"  figure: {path}")


def run(args: argparse.Namespace, out_dir: Path) -> tuple[Series, Jobs]:
    """The show for ``args.minutes`` after its vehicles are ready, sampled every ``sample_s``."""
    path, show = derived_show(
        SHOW, out_dir, time_scale=args.time_scale, fleet_hosts=args.fleet_hosts
    )
    series, jobs = Series(), Jobs()
    with (
        ShowRun(path, show, log_dir=out_dir / "logs") as show_run,
        show_run.client() as session,
        Stagehand(session, show_run.keys, period_s=5.0),
    ):
        _sub = subscribe(session, show_run.keys.jobs_all, JobState, jobs.on_job)
        wait_ready(show_run, session, len(show.vehicles), timeout_s=180.0)
        start = time.monotonic()
        series.take(0.0, show_run)
        stop = threading.Event()
        feeder = threading.Thread(
            target=keep_waiting, args=(stop, show_run, session, jobs, args.waiting), daemon=True
        )
        feeder.start()
        end = start + args.minutes * 60.0
        while (now := time.monotonic()) < end:
            time.sleep(min(args.sample_s, end - now))
            series.take(time.monotonic() - start, show_run)
        stop.set()
        feeder.join(timeout=30.0)
    return series, jobs


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=10.0, help="after ready (10)")
    parser.add_argument("--time-scale", type=float, default=4.0, help="show time_scale (4)")
    parser.add_argument("--waiting", type=int, default=8, help="characters kept waiting (8)")
    parser.add_argument("--sample-s", type=float, default=10.0, help="sampling period (10 s)")
    parser.add_argument(
        "--fleet-hosts",
        type=int,
        default=0,
        help="the show's fleet_hosts: its vehicles in so many processes sharing their planning"
        " workers (0, the Airshow's: an agent and a worker per vehicle)",
    )
    parser.add_argument("--warmup-s", type=float, default=120.0, help="slopes after this (120 s)")
    parser.add_argument("--png", type=Path, help="draw the memory over the run here")
    args = parser.parse_args()
    load_before = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp:
        series, jobs = run(args, Path(tmp))
    counts = jobs.counts()
    print(
        f"memory: {SHOW.name} at time_scale {args.time_scale:g}, fleet_hosts"
        f" {args.fleet_hosts}, {args.minutes:g} min after"
        f" ready, {counts['done']} done, {counts['failed']} failed; load (1 min)"
        f" {load_before:.1f} at start, {os.getloadavg()[0]:.1f} at the end; MiB"
    )
    report(series, args.warmup_s)
    verdict(series, args.warmup_s)
    if args.png:
        figure(series, args.png)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

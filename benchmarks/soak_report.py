"""The soak's report (``bench_soak.py``): its samples printed as tables, and drawn (``--png``).

    python benchmarks/bench_soak.py --minutes 15 --png soak.png

While the soak runs, one line a minute: jobs done and failed, RSS per process. After it, per
process RSS at start, after warm-up and at the end, its peak and its least-squares slope after
warm-up, the same for its anonymous memory; per storage its size and growth after warm-up; the
characters written per hour, failed jobs and restarts; the job pictures and how late they came.
Memory and disk in MiB (:data:`MIB`), slopes per hour.
"""

from __future__ import annotations

import argparse
import statistics
from pathlib import Path
from typing import TYPE_CHECKING

from bench_show import SHOW

if TYPE_CHECKING:
    from bench_soak import Jobs, Pictures, Samples

MIB = 1024.0 * 1024.0


def slope_per_h(points: list[tuple[float, int]], after_s: float) -> float | None:
    """Least-squares slope of the points at or after ``after_s``, in units per hour."""
    kept = [(t, v) for t, v in points if t >= after_s]
    if len(kept) < 3:
        return None
    return statistics.linear_regression([t for t, _ in kept], [v for _, v in kept]).slope * 3600


def at(points: list[tuple[float, int]], t_s: float) -> int:
    """The first value sampled at or after ``t_s`` (the last one if none)."""
    return next((v for t, v in points if t >= t_s), points[-1][1])


def progress(samples: Samples, jobs: Jobs) -> None:
    """Print the minutes since the show was ready, jobs done and failed, and each process's
    latest RSS in MiB."""
    rss = ", ".join(f"{name} {points[-1][1] / MIB:.0f}" for name, points in samples.rss.items())
    counts = jobs.counts()
    print(
        f"  {samples.t_s[-1] / 60:5.1f} min: {counts['done']} done, {counts['failed']} failed;"
        f" RSS MiB: {rss}",
        flush=True,
    )


def report(
    args: argparse.Namespace, samples: Samples, jobs: Jobs, restarts: dict[str, int]
) -> None:
    """Print the table of RSS and disk per process and storage, and the show's throughput."""
    warm_s = args.warmup_minutes * 60.0
    hours = samples.t_s[-1] / 3600.0
    print(
        f"soak: {SHOW.name} at time_scale {args.time_scale:g}, {samples.t_s[-1] / 60:.1f} min,"
        f" warm-up {args.warmup_minutes:g} min, {len(samples.t_s)} samples"
    )
    print(
        "  process          RSS MiB: start  warm   end  peak  slope after warm-up"
        "   anonymous MiB: end  slope after warm-up"
    )
    for name, points in samples.rss.items():
        anon = samples.anon[name]
        print(
            f"  {name:18} {points[0][1] / MIB:12.0f} {at(points, warm_s) / MIB:5.0f}"
            f" {points[-1][1] / MIB:5.0f} {max(v for _, v in points) / MIB:5.0f}"
            f"  {_slope(points, warm_s):>15} {anon[-1][1] / MIB:22.0f}"
            f"  {_slope(anon, warm_s):>15}"
        )
    print("  storage            start MiB  warm MiB  end MiB  growth after warm-up")
    for name, points in samples.disk.items():
        slope = slope_per_h(points, warm_s)
        shown = "-" if slope is None else f"{slope / MIB:+7.2f} MiB/h"
        print(
            f"  {name:18} {points[0][1] / MIB:9.2f} {at(points, warm_s) / MIB:9.2f}"
            f" {points[-1][1] / MIB:8.2f}  {shown}"
        )
    counts = jobs.counts()
    done_slope = slope_per_h(samples.done, warm_s)
    print(
        f"  characters: {counts['done']} done ({counts['done'] / hours:.0f}/h overall,"
        f" {done_slope or 0.0:.0f}/h after warm-up), {counts['failed']} failed,"
        f" {counts['cancelled']} cancelled; restarts: "
        + (", ".join(f"{n} {k}" for n, k in restarts.items() if k) or "none")
    )
    after = counts["done"] - at(samples.done, warm_s)
    if after > 0 and "orchestrator" in samples.rss:
        rss, anon = samples.rss["orchestrator"], samples.anon["orchestrator"]
        per_job = [(s[-1][1] - at(s, warm_s)) / after / 1024 for s in (rss, anon)]
        print(
            f"  orchestrator growth after warm-up per job: RSS {per_job[0]:+.1f} KiB,"
            f" anonymous {per_job[1]:+.1f} KiB"
        )


def report_pictures(pictures: Pictures, waited_s: float) -> None:
    """Print how many jobs have their picture and how late the pictures came."""
    late = [s for _, s in pictures.late_s]
    drawn = len(late)
    print(
        f"  pictures: {drawn} of {pictures.jobs} job directories ({pictures.waiting} still"
        f" waiting after {waited_s:.0f} s more)"
    )
    if late:
        print(
            f"  picture after its job: median {statistics.median(late):.1f} s, max"
            f" {max(late):.1f} s; the last job's {late[-1]:.1f} s"
        )


def _slope(points: list[tuple[float, int]], after_s: float) -> str:
    """The slope after ``after_s`` as the table shows it, in MiB/h ("-": too few points)."""
    slope = slope_per_h(points, after_s)
    return "-" if slope is None else f"{slope / MIB:+7.1f} MiB/h"


def plot(samples: Samples, path: Path, warm_s: float) -> None:
    """RSS over time per process, the end of warm-up marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 5))
    for name, points in samples.rss.items():
        ax.plot([t / 60 for t, _ in points], [v / MIB for _, v in points], label=name)
    ax.axvline(warm_s / 60, color="grey", linestyle="--", label="end of warm-up")
    ax.set_xlabel("time [min]")
    ax.set_ylabel("RSS [MiB]")
    ax.set_title("Airshow soak: resident memory per process")
    ax.legend(fontsize=8, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)

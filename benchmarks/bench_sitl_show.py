"""A SITL show at show scale, run as the README runs it, and what it wrote.

    .venv/bin/python benchmarks/bench_sitl_show.py shows/sitl-airshow.yaml [--busy 4]
        [--chars 火 日 ...] [--rehearsal 1] [--px4-imu-vibration stock]

``scripts/sitl/start.py`` starts one autopilot per vehicle, ``skyquill up --headless`` the show,
then (benchmarks/sitl_show.py): a rehearsal round (``--rehearsal`` characters per vehicle, 口:
each vehicle's tracking identified before the public's characters; not counted), then the
held-out characters (default 12: eight Chinese, four Latin, none of them in the tests), queued at
once so that the vehicles write side by side in rounds. Printed per job: vehicle, character,
state, the pace chosen (stretch of the limits' duration), the error predicted for it and the one
flown (pen-down RMSE), ink IoU; then the medians, the worst IoU, jobs not done, the alerts a
show's operator would see (``not_settled``, faults, arming refused) and the load beside it.
``--busy N`` runs N busy loops beside the show (the issue's "load 4"). A figure of predicted
against flown error goes to ``out/bench/sitl-show-<show>.png``.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from sitl_show import ShowRun, running  # noqa: E402  (beside this file)

HELD_OUT = ("火", "日", "月", "天", "云", "田", "王", "石", "R", "K", "W", "G")
REHEARSAL = "口"
JOB_LIMIT_S = 240.0
"""Longest time one round of characters may take, per character queued on a vehicle."""
WATCHED = (
    "not_settled",
    "vehicle_fault",
    "geofence",
    "deviation",
    "takeoff_refused",
    "preflight",
    "battery_swap",
)
"""Event kinds an operator would act on (faults, aborts) or a show would lose time to."""


def _busy(count: int) -> list[subprocess.Popen[bytes]]:
    loop = "while True:\n    pass\n"
    return [subprocess.Popen([sys.executable, "-c", loop]) for _ in range(count)]


def _round(run: ShowRun, texts: list[str], vehicles: int, ended_before: int) -> list[str]:
    ids = [run.submit(text) for text in texts]
    rounds = -(-len(texts) // max(vehicles, 1))
    run.wait_jobs(ended_before + len(texts), JOB_LIMIT_S * rounds + 120.0)
    return ids


def _row(job: dict[str, Any]) -> str:
    m = job.get("metrics") or {}
    extra = m.get("extra") or {}
    predicted = extra.get("pace_predicted_rmse_pen_down_m")
    cells = [
        f"{job.get('vehicle_id') or '-':6}",
        f"{job['label']:>4}",
        f"{job['state']:>8}",
        f"{extra.get('pace_stretch', float('nan')):8.2f}",
        f"{'first':>10}" if predicted is None else f"{1000 * predicted:10.1f}",
        f"{1000 * m['rmse_pen_down_m']:7.1f}" if m else "      -",
        f"{m['iou']:6.2f}" if m.get("iou") is not None else "     -",
        f"{m['duration_s']:7.1f}" if m else "      -",
    ]
    return "  " + " ".join(cells)


def report(
    jobs: list[dict[str, Any]], events: list[dict[str, Any]], loads: list[float]
) -> dict[str, Any]:
    """Print the table and the summary; the summary's figures."""
    print(f"  {'vehicle':6} {'char':>4} {'state':>8} {'stretch':>8} {'predicted':>10} "
          f"{'flown':>7} {'IoU':>6} {'time':>7}   [mm, s]")  # fmt: skip
    for job in jobs:
        print(_row(job))
    done = [j for j in jobs if j["state"] == "done" and j.get("metrics")]
    rmse = [1000 * j["metrics"]["rmse_pen_down_m"] for j in done]
    ious = [j["metrics"]["iou"] for j in done if j["metrics"].get("iou") is not None]
    ratios = [
        j["metrics"]["rmse_pen_down_m"] / j["metrics"]["extra"]["pace_predicted_rmse_pen_down_m"]
        for j in done
        if "pace_predicted_rmse_pen_down_m" in (j["metrics"].get("extra") or {})
    ]
    watched = [e for e in events if e["kind"] in WATCHED]
    summary = {
        "done": len(done),
        "jobs": len(jobs),
        "rmse_median_mm": statistics.median(rmse) if rmse else None,
        "iou_median": statistics.median(ious) if ious else None,
        "iou_worst": min(ious) if ious else None,
        "flown_over_predicted_median": statistics.median(ratios) if ratios else None,
        "watched_events": len(watched),
        "load": (min(loads), max(loads)) if loads else None,
    }
    print(f"  {summary['done']} of {summary['jobs']} done; pen-down RMSE median "
          f"{_fmt(summary['rmse_median_mm'], '.1f')} mm; IoU median "
          f"{_fmt(summary['iou_median'], '.2f')}, worst {_fmt(summary['iou_worst'], '.2f')}; "
          f"flown / predicted median {_fmt(summary['flown_over_predicted_median'], '.2f')}; "
          f"load (1 min) {loads and f'{min(loads):.1f}-{max(loads):.1f}'}")  # fmt: skip
    for e in watched:
        print(f"  event {e['kind']} {e.get('vehicle_id') or '-'}: {e['message']}")
    return summary


def _fmt(value: float | None, spec: str) -> str:
    return "-" if value is None else format(value, spec)


def figure(jobs: list[dict[str, Any]], path: Path, title: str) -> None:
    """Predicted against flown pen-down RMSE per job, one colour per vehicle."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 5))
    for vehicle in sorted({j.get("vehicle_id") or "-" for j in jobs}):
        pairs = [
            (1000 * j["metrics"]["extra"]["pace_predicted_rmse_pen_down_m"],
             1000 * j["metrics"]["rmse_pen_down_m"])
            for j in jobs
            if j.get("vehicle_id") == vehicle and j.get("metrics")
            and "pace_predicted_rmse_pen_down_m" in (j["metrics"].get("extra") or {})
        ]  # fmt: skip
        if pairs:
            ax.scatter(*zip(*pairs, strict=True), label=vehicle)
    ax.plot([0, 20], [0, 20], color="grey", lw=0.8)
    ax.set(xlabel="predicted pen-down RMSE [mm]", ylabel="flown pen-down RMSE [mm]", title=title)
    ax.legend()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    print(f"  figure: {path}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("show", type=Path, nargs="?", default=ROOT / "shows/sitl-airshow.yaml")
    parser.add_argument("--chars", nargs="+", default=list(HELD_OUT))
    parser.add_argument("--rehearsal", type=int, default=1, help="characters per vehicle first")
    parser.add_argument("--busy", type=int, default=0, help="busy loops beside the show")
    parser.add_argument(
        "--px4-imu-vibration",
        metavar="F|stock",
        help="PX4 SIH's airframe, start.py's option (stock: SIH as shipped)",
    )
    args = parser.parse_args()
    vibration = args.px4_imu_vibration
    sitl_args = () if vibration is None else ("--px4-imu-vibration", vibration)
    name = args.show.stem + ("" if vibration is None else f"-vibration-{vibration}")
    busy = _busy(args.busy)
    try:
        with running(args.show.resolve(), sitl_args=sitl_args) as run:
            vehicles = len(run.status()["vehicles"])
            print(f"{args.show.name}: {vehicles} vehicles up; folder {run.folder}", flush=True)
            rehearsal = [REHEARSAL] * (vehicles * args.rehearsal)
            ended = 0
            if rehearsal:
                _round(run, rehearsal, vehicles, 0)
                ended = len(rehearsal)
            t0 = time.monotonic()
            run.loads.clear()
            ids = _round(run, args.chars, vehicles, ended)
            jobs = [j for j in run.status()["jobs"] if j["job_id"] in ids]
            print(f"held-out characters written in {time.monotonic() - t0:.0f} s")
            report(jobs, run.events(), run.loads)
            print(f"  battery swaps the crew confirmed: {len(run.swaps)} {run.swaps}")
            figure(jobs, ROOT / "out/bench" / f"sitl-show-{name}.png", name)
    finally:
        for proc in busy:
            proc.kill()
    return 0


if __name__ == "__main__":
    sys.exit(main())

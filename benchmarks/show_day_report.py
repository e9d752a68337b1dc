"""``bench_show --day``: the Airshow show's day with batteries and sheets beside the same day
without them (the same visitors, the same seed), printed and drawn (:mod:`show_day`).

Arrivals: the Airshow paper (Phang et al. 2015, section 5) says the system ran through the six
days of the Singapore Airshow 2014 with four vehicles writing four characters at once, but not
how many characters were written or how many visitors came: the rate is an assumption,
``--arrivals`` per hour (default :data:`ARRIVALS_PER_H`).
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

from show_day import CAUSES, Crew, DayResult, Phases, ShowDay, without_costs

from orchestrator.core import CoreConfig
from orchestrator.outputs import core_config
from orchestrator.sheets import BoardSheets
from showfile.models import Show
from vehicles.batteries import kind_battery

ARRIVALS_PER_H = 150.0
"""Visitors handing in a character per hour: an assumption (one every 24 s at the booth)."""
FIGURE = Path("out/bench/bench-show-day.png")
SEED = 2014


def day_config(show: Show) -> CoreConfig:
    """The show's Book policy with the Airshow's sheets: each character is a sheet taken away
    (issue 32)."""
    config = core_config(show)
    return replace(config, boards=tuple((b.id, BoardSheets("per_character")) for b in show.boards))


def run_days(
    show: Show, phases: dict[str, Phases], hours: float, arrivals_per_h: float | None
) -> tuple[DayResult, DayResult]:
    """The day with batteries and sheets, and its peer without."""
    corpus = "".join(phases)
    config = day_config(show)
    battery = kind_battery("quadrotor-brush")
    crew = Crew()
    with_costs = ShowDay(config, phases.__getitem__, battery, crew, SEED)
    peer = ShowDay(without_costs(config), phases.__getitem__, None, crew, SEED)
    return (with_costs.run(hours, arrivals_per_h, corpus), peer.run(hours, arrivals_per_h, corpus))


def print_day(day: DayResult, peer: DayResult, vehicles: int, crew: Crew) -> None:
    print(
        f"  crew turnaround: log-normal, median {crew.sheet_median_s:g} s a sheet, "
        f"{crew.swap_median_s:g} s a swap, sigma {crew.sigma:g}"
    )
    print(f"  visitors: {day.submitted} characters handed in, {day.refused} refused (queue full)")
    for name, result in (("with batteries and sheets", day), ("without (peer)", peer)):
        written = len(result.written_at_s)
        print(
            f"  {name:26} {written:5d} characters, {written / result.hours:6.1f} per hour;"
            f" swaps {result.swaps}, sheets {result.sheets}"
        )
        print(f"    per hour: {' '.join(f'{n:3d}' for n in result.per_hour())}")
        fleet_s = vehicles * result.hours * 3600.0
        shares = ", ".join(
            f"{cause} {result.lost_s[cause] / 3600.0:.2f} h ({result.lost_s[cause] / fleet_s:.0%})"
            for cause in ("writing", *CAUSES)
        )
        print(f"    vehicle-hours: {shares}")
    ratio = len(day.written_at_s) / max(1, len(peer.written_at_s))
    print(f"  batteries and sheets: x{ratio:.3f} the characters of the same day without them")


def _visitors(arrivals_per_h: float | None) -> str:
    if arrivals_per_h is None:
        return "more visitors than it can serve (queue kept full)"
    return f"{arrivals_per_h:g} visitors per hour"


def draw_days(days: list[tuple[float | None, DayResult, DayResult]], path: Path) -> None:
    """Per arrival rate: characters per hour over the day, and the fleet's hours by cause."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(days), 2, figsize=(11, 4 * len(days)), squeeze=False)
    causes = ("writing", *CAUSES)
    for (arrivals_per_h, day, peer), (rate, lost) in zip(days, axes, strict=True):
        hours = range(len(day.per_hour()) + 1)
        for result, label, style in (
            (day, "with batteries and sheets", "-"),
            (peer, "without (peer)", "--"),
        ):
            counts = result.per_hour()
            rate.step(hours, [*counts, counts[-1]], where="post", label=label, linestyle=style)
        rate.set(
            xlabel="hour of the show",
            ylabel="characters written",
            ylim=(0, None),
            title=f"characters per hour, {_visitors(arrivals_per_h)}",
        )
        rate.legend(loc="lower right")
        for k, (name, result) in enumerate((("with", day), ("without", peer))):
            xs = [i + (k - 0.5) * 0.4 for i in range(len(causes))]
            lost.bar(xs, [result.lost_s[c] / 3600.0 for c in causes], width=0.4, label=name)
        lost.set_xticks(range(len(causes)), causes, rotation=30, ha="right")
        lost.set(ylabel="vehicle-hours", title="where the fleet's day went")
        lost.legend()
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def day(show: Show, phases: dict[str, Phases], hours: float, arrivals_per_h: float) -> None:
    """Run, print and draw the day at the assumed arrival rate and with a queue never empty."""
    days = []
    for rate_per_h in (arrivals_per_h, None):  # None: the queue never empty
        start = time.perf_counter()
        result, peer = run_days(show, phases, hours, rate_per_h)
        elapsed_s = time.perf_counter() - start
        print(
            f"show day: {hours:g} h of show time, {_visitors(rate_per_h)}, "
            f"{len(show.vehicles)} vehicles, seed {SEED}; simulated in {elapsed_s:.1f} s"
        )
        print_day(result, peer, len(show.vehicles), Crew())
        days.append((rate_per_h, result, peer))
    draw_days(days, FIGURE)
    print(f"  figure: {FIGURE}")

"""Every input the quadrotor can write, planned by the wall writer: planning failures and time.

    nice -n 10 python benchmarks/bench_wall_corpus.py            # 200+ inputs, 1 m letters
    nice -n 10 python benchmarks/bench_wall_corpus.py --quick    # a dozen (smoke run)
    nice -n 10 python benchmarks/bench_wall_corpus.py --paper    # the paper's eq. 7 (no corridors)

The corpus (issue 33): Chinese characters of the glyph set (the 100 most common that it has),
the Latin alphabet and digits, Latin words in a print and a script (cursive) Hershey font,
cursive strokes (one stroke of loops, a handwritten run of "l"), spirals (2 to 8 turns, in and
out, either way), and kiosk drawings at the kiosk's limits (``kiosk.limits.SubmissionLimits``:
60 strokes and 5000 points in all, one stroke of 5000 points, jittery like a finger on glass).
Each is laid out 1 m x 1 m with the typed-text width profile and planned cold (no period reused).
Printed per input: planning CPU seconds, contact periods (after splitting long strokes), the
plan's IoU flown perfectly and its pen-down path's largest distance from the strokes; then the
failures (with their one-line errors), the median and worst CPU per letter, and the load.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np

from kiosk.limits import SubmissionLimits
from planner.errors import PlannerError
from planner.glyphs.glyph import Glyph
from planner.glyphs.layout import fit_to_area
from planner.glyphs.text import has_glyph, text_glyph
from vehicles.hexarotor_sponge.kind import WallSettings, with_default_widths
from vehicles.hexarotor_sponge.limits import Limits
from vehicles.hexarotor_sponge.metrics import plan_fidelity
from vehicles.hexarotor_sponge.nlp import solve_period
from vehicles.hexarotor_sponge.plan import PlanSettings, plan_writing
from vehicles.kind import StrokeInput
from vehicles.surface import Surface

SURFACE = Surface.of("vertical", (0.0, 3.0, 2.0), 0.0)
SIZE_M = 1.0
"""Letters are laid out in a square of this side in [m] (the issue's 1 m letters)."""
# The most common characters by frequency of use (modern corpora), as in bench_planner.py.
COMMON_HANZI = (
    "的一是不了人我在有他这为之大来以个中上们到说国和地也子时道出而要于就下得可你年生自会那后能对着"
    "事其里所去行过家十用发天如然作方成者多日都三小军二无同么经法当起与好看学进种将还分此心前面又定"
)
LATIN = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789&"
WORDS = ("wall", "ink", "minimum", "letter", "spiral", "quill", "hello", "cursive", "loop", "sky")
SCRIPT_FONT = "scripts"
"""Hershey script simplex: joined-up (cursive) Latin letters."""
QUICK = ("永", "8", "R", "&", "中", "word:minimum", "script:cursive", "cursive:6",
         "spiral:5:out:ccw", "kiosk:strokes:0", "kiosk:points:0")  # fmt: skip


def corpus() -> list[str]:
    """The corpus's names (each says how :func:`strokes_of` makes its strokes)."""
    hanzi = [c for c in COMMON_HANZI if has_glyph(c)][:100]
    names = [*hanzi, *LATIN]
    names += [f"word:{w}" for w in WORDS] + [f"script:{w}" for w in WORDS]
    names += [f"cursive:{loops}" for loops in (2, 3, 4, 5, 6, 7, 8, 10, 12, 14)]
    names += [
        f"spiral:{turns}:{way}:{sense}"
        for turns in (2, 3, 5, 8)
        for way in ("in", "out")
        for sense in ("ccw", "cw")
    ]
    names += [f"kiosk:{what}:{seed}" for what in ("strokes", "points", "dots") for seed in range(4)]
    return names


def strokes_of(name: str) -> list[StrokeInput]:
    """The strokes of corpus entry ``name`` laid out in the :data:`SIZE_M` square, with the
    typed-text width profile."""
    kind, _, rest = name.partition(":")
    if not rest:
        glyph = text_glyph(name)
    elif kind in ("word", "script"):
        glyph = text_glyph(rest, latin_font="futural" if kind == "word" else SCRIPT_FONT)
    else:
        drawn = tuple(_drawn(kind, rest))
        glyph = Glyph(drawn, (None,) * len(drawn), "m", name, "bench_wall_corpus")
    laid = fit_to_area(glyph, width_m=SIZE_M, height_m=SIZE_M)
    raw = [StrokeInput(np.asarray(s, dtype=np.float64)) for s in laid.strokes]
    return with_default_widths(raw, WallSettings())


def _drawn(kind: str, spec: str) -> Iterator[np.ndarray]:
    """Strokes drawn by formula or at random (a kiosk's finger)."""
    parts = spec.split(":")
    if kind == "cursive":  # a prolate trochoid: loops joined by upstrokes, as a run of "l"
        loops = int(parts[0])
        t = np.linspace(0.0, 2.0 * np.pi * loops, 60 * loops)
        yield np.column_stack([t / (2.0 * np.pi) - 0.25 * np.sin(t), -np.cos(t)])
    elif kind == "spiral":  # Archimedean, from 3 % of its radius
        turns, way, sense = int(parts[0]), parts[1], parts[2]
        theta = np.linspace(0.0, 2.0 * np.pi * turns, 100 * turns)
        radius = 0.03 + theta / theta[-1]
        xy = np.column_stack([radius * np.cos(theta), radius * np.sin(theta)])
        xy = xy if way == "out" else xy[::-1]
        yield xy if sense == "ccw" else xy * [1.0, -1.0]
    else:
        yield from _kiosk(parts[0], int(parts[1]))


def _kiosk(what: str, seed: int) -> Iterator[np.ndarray]:
    """A drawing at the kiosk's limits: ``strokes``, the most strokes with the most points in
    all; ``points``, one stroke of the most points; ``dots``, the most strokes of two points.
    Finger paths: smooth random walks with a pixel's jitter (a 1000 px canvas)."""
    limits = SubmissionLimits()
    rng = np.random.default_rng(seed)
    count = 1 if what == "points" else limits.max_strokes
    points = 2 if what == "dots" else limits.max_points // count
    for _ in range(count):
        heading = rng.uniform(0.0, 2.0 * np.pi) + np.cumsum(rng.normal(0.0, 0.08, points))
        step = rng.uniform(1.0, 3.0) if what == "points" else rng.uniform(2.0, 12.0)
        xy = rng.uniform(0.0, 1000.0, 2) + np.cumsum(
            step * np.column_stack([np.cos(heading), np.sin(heading)]), axis=0
        )
        yield xy + rng.normal(0.0, 0.5, xy.shape)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a dozen inputs")
    parser.add_argument("--paper", action="store_true", help="the paper's eq. 7, no corridors")
    args = parser.parse_args()
    names = list(QUICK) if args.quick else corpus()
    settings = PlanSettings()
    if args.paper:
        settings = replace(settings, limits=Limits(corridor_m=None))
    width = settings.default_width_m
    cpu_s: list[float] = []
    failures: list[str] = []
    print(f"{len(names)} inputs, {SIZE_M:g} m, load {os.getloadavg()[0]:.2f}", flush=True)
    for name in names:
        strokes = strokes_of(name)
        points = sum(s.xy_m.shape[0] for s in strokes)
        started = time.process_time()
        try:
            plan = plan_writing(strokes, SURFACE, settings, solve=solve_period)
        except PlannerError as err:
            failures.append(f"{name}: {err}")
            print(f"{name:20s} FAILED after {time.process_time() - started:.2f} s CPU: {err}")
            continue
        cpu_s.append(time.process_time() - started)
        fidelity = plan_fidelity(plan, width)
        periods = [p for p in plan.feasibility["periods"] if p["contact"]]
        print(
            f"{name:20s} {len(strokes):3d} strokes {points:5d} points: {cpu_s[-1]:6.2f} s CPU, "
            f"{len(periods):3d} contact periods, {plan.duration_s:6.1f} s of writing, "
            f"plan IoU {fidelity['plan_iou']:.3f}, "
            f"max {fidelity['plan_max_to_strokes_m'] * 1000:.2f} mm from the strokes",
            flush=True,
        )
    print(
        f"\n{len(failures)} planning failures of {len(names)} inputs; CPU per input: median "
        f"{statistics.median(cpu_s):.2f} s, worst {max(cpu_s):.2f} s; load {os.getloadavg()[0]:.2f}"
    )
    for line in failures:
        print(f"  {line}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())

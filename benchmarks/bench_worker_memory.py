"""What one planning worker keeps per job, without a show: the Airshow's jobs through a worker's
real requests (``prepare``, ``measure``, ``archive``), each flown by a made-up vehicle that lags
its plan, the worker's memory after each.

    python benchmarks/bench_worker_memory.py                  # 40 jobs of the soak's corpus
    python benchmarks/bench_worker_memory.py --distinct 500   # 500 different characters
    python benchmarks/bench_worker_memory.py --trace 21       # what grew from job 21 on
    python benchmarks/bench_worker_memory.py --process        # a real worker process

By default the :class:`vehicle_agent.plan_worker.Worker` runs in this very process, its
end-of-job step (``give_back``) after each job as ``serve`` does, and its pictures are not drawn
(a drawing process lives apart, ``vehicle_agent/picture_process.py``: each order is removed as
if drawn). Printed per job: ``RssAnon`` (the heap a leak grows) and ``VmRSS`` in MiB, glibc's
heap in use and free inside its arenas (what fragmentation holds), and at the end each planner
cache's fill and hits. ``--trace K``: the allocation sites that grew from job K to the last
(tracemalloc, 12 frames: planning runs 5-10x slower). ``--process``: a worker process started as
an agent starts it, its pictures drawn by real drawing processes, its ``RssAnon`` and ``VmRSS``.
Light: one core, 0.05-0.1 s CPU per job in this process (quiet machine).
"""

from __future__ import annotations

import argparse
import asyncio
import ctypes
import functools
import itertools
import sys
import tempfile
import time
import tracemalloc
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE.parent / "tests"))

from job_traces import recorded_trace  # noqa: E402

from bus.messages import JobAssignment  # noqa: E402
from cli.showrun import derived_show  # noqa: E402
from vehicle_agent import job_picture  # noqa: E402
from vehicle_agent.job_runner import PreparedJob  # noqa: E402
from vehicle_agent.picture_process import BatchOutcome  # noqa: E402
from vehicle_agent.plan_worker import Worker, give_back  # noqa: E402
from vehicle_agent.trace import JobTrace  # noqa: E402

SHOW = HERE.parent / "shows" / "airshow-2014.yaml"
CORPUS = "ABQRSgkw" + "永光马和我的是人大中国天"
"""``bench_soak.py``'s corpus: what the memory benchmark's show plans, round and round."""
DISTINCT_FROM = 1000
"""``--distinct N`` takes the hanzi store's characters from this one on, in code-point order."""
LAG_S = 0.01
"""The made-up vehicle's first-order lag in [s] behind its plan."""
NOISE_M = 0.001
"""Its position noise in [m] (norm of the standard deviations)."""
TOP = 12
"""Allocation sites printed with ``--trace``."""
MIB = 1024.0 * 1024.0


class MallInfo2(ctypes.Structure):
    """glibc's ``struct mallinfo2`` (2.33+): ten ``size_t`` fields."""

    _fields_ = [
        (name, ctypes.c_size_t)
        for name in (
            *("arena", "ordblks", "smblks", "hblks", "hblkhd"),
            *("usmblks", "fsmblks", "uordblks", "fordblks", "keepcost"),
        )
    ]


def malloc_mib() -> tuple[float, float]:
    """This process's glibc heap in [MiB]: in use (``uordblks`` plus mmapped ``hblkhd``) and
    free inside its arenas (``fordblks``, what fragmentation holds); NaN where glibc cannot say.
    Python's own small-object arenas are not in it (they are mmapped apart)."""
    try:
        call = ctypes.CDLL("libc.so.6").mallinfo2
    except (OSError, AttributeError):
        return float("nan"), float("nan")
    call.restype = MallInfo2
    info = call()
    return (info.uordblks + info.hblkhd) / MIB, info.fordblks / MIB


def status_mib(pid: int | str = "self") -> dict[str, float]:
    """``RssAnon`` and ``VmRSS`` of ``pid`` in [MiB]."""
    found = {}
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        name, _, value = line.partition(":")
        if name in ("RssAnon", "VmRSS"):
            found[name] = int(value.split()[0]) / 1024.0
    return found


def flown(prepared: PreparedJob, board_z_m: float, seed: int) -> JobTrace:
    """A flight of a vehicle that follows its plan through a first-order lag of :data:`LAG_S`
    plus :data:`NOISE_M` of noise (each trace differs, as a simulated flight's does), the
    brush tip on the board while writing."""
    s = prepared.samples
    dt_s = float(s.t_s[1] - s.t_s[0])
    body_m_enu = np.empty_like(s.position_m_enu)
    body_m_enu[0] = s.position_m_enu[0]
    for k in range(1, body_m_enu.shape[0]):
        lag = s.position_m_enu[k - 1] - body_m_enu[k - 1]
        body_m_enu[k] = body_m_enu[k - 1] + dt_s / LAG_S * lag
    noise = np.random.default_rng(seed).normal(0.0, NOISE_M / np.sqrt(3.0), body_m_enu.shape)
    body_m_enu += noise
    tip_m_enu = body_m_enu.copy()
    tip_m_enu[:, 2] = board_z_m
    width_m = np.where(s.pen_down, 0.02, 0.0)
    ref = s.position_m_enu
    args = (s.t_s, body_m_enu, s.velocity_mps_enu, ref, s.pen_down, s.pen_down)
    trace: JobTrace = recorded_trace(prepared.job_id, 1, *args, tip_m_enu, width_m)
    return trace


def undrawn(job_dirs: Sequence[Path]) -> BatchOutcome:
    """Stand-in for the drawing process: every order removed, as if drawn."""
    for job_dir in job_dirs:
        (job_dir / job_picture.ORDER_NAME).unlink(missing_ok=True)
    return BatchOutcome(drawn=list(job_dirs), exit_code=0, cpu_s=0.0)


def line(k: int, text: str, now: dict[str, float], base: dict[str, float]) -> str:
    return (
        f"job {k:3d} {text}: RssAnon {now['RssAnon']:6.1f} MiB"
        f" ({now['RssAnon'] - base['RssAnon']:+6.1f}), VmRSS {now['VmRSS']:6.1f}"
    )


def in_this_process(args: argparse.Namespace, corpus: str, tmp: Path) -> None:
    """The jobs through a :class:`Worker` of this process (pictures not drawn)."""
    job_picture.draw_apart = undrawn  # type: ignore[attr-defined]  # patched: drawn nowhere
    _, show = derived_show(SHOW, tmp)
    vehicle = show.vehicles[0]
    board_z_m = show.board(vehicle.board).center_m_enu[2]
    worker = Worker()
    worker.handle(("init", show, vehicle.id, 1.0))
    worker.handle(("warm",))
    give_back()
    base = status_mib()
    print(f"warm: RssAnon {base['RssAnon']:.1f} MiB, VmRSS {base['VmRSS']:.1f}")
    first = None
    for k, text in enumerate(itertools.islice(itertools.cycle(corpus), args.jobs), start=1):
        if k == args.trace:
            tracemalloc.start(12)
        started_s = time.process_time()
        prepared = worker.handle(("prepare", JobAssignment(job_id=f"j{k}", text=text)))
        trace = flown(prepared, board_z_m, seed=k)
        metrics = worker.handle(("measure", prepared, trace))
        worker.handle(("archive", prepared, trace, metrics))
        del prepared, trace, metrics
        give_back()
        if k == args.trace:
            first = tracemalloc.take_snapshot()
        used_mib, free_mib = malloc_mib()
        print(
            f"{line(k, text, status_mib(), base)}; malloc in use {used_mib:5.1f}, free"
            f" {free_mib:4.1f}; cpu {time.process_time() - started_s:.2f} s",
            flush=True,
        )
    worker.close()
    if first is not None:
        print_grown(first, args.trace)
    print_caches()


def print_grown(first: tracemalloc.Snapshot, since: int) -> None:
    """The allocation sites that grew most since ``first``."""
    print(f"grown since job {since} (tracemalloc):")
    for stat in tracemalloc.take_snapshot().compare_to(first, "traceback")[:TOP]:
        print(f"{stat.size_diff / 1024:+10.1f} KiB {stat.count_diff:+7d} blocks")
        print("\n".join(f"      {text}" for text in stat.traceback.format()[-8:]))


def print_caches() -> None:
    """Each ``lru_cache`` of the project's modules that was used: its fill and hits."""
    print("caches:")
    for name, module in sorted(sys.modules.items()):
        if name.split(".")[0] not in ("planner", "vehicles", "vehicle_agent", "sim", "bus"):
            continue
        for attr, value in vars(module).items():
            if not isinstance(value, functools._lru_cache_wrapper):
                continue
            info = value.cache_info()
            if getattr(value, "__module__", None) == name and info.hits + info.misses:
                print(
                    f"  {name}.{attr}: {info.currsize}/{info.maxsize} kept,"
                    f" {info.hits} hits, {info.misses} misses"
                )


async def in_a_worker_process(args: argparse.Namespace, corpus: str, tmp: Path) -> None:
    """The jobs through a real worker process (:class:`ProcessJobWork`), its pictures drawn by
    real drawing processes (about 1 s CPU per batch). Read right after ``archive`` answers,
    the worker may not have given its heap back yet (it does after answering)."""
    from vehicle_agent.worker_client import ProcessJobWork

    _, show = derived_show(SHOW, tmp)
    vehicle = show.vehicles[0]
    board_z_m = show.board(vehicle.board).center_m_enu[2]
    work = ProcessJobWork(show, vehicle.id, 1.0)
    try:
        await work.warm()
        pid: Any = work.pid
        base = status_mib(pid)
        print(f"warm: RssAnon {base['RssAnon']:.1f} MiB, VmRSS {base['VmRSS']:.1f}")
        for k, text in enumerate(itertools.islice(itertools.cycle(corpus), args.jobs), start=1):
            prepared = await work.prepare(JobAssignment(job_id=f"j{k}", text=text))
            trace = flown(prepared, board_z_m, seed=k)
            metrics = await work.measure(prepared, trace)
            await work.archive(prepared, trace, metrics)
            print(line(k, text, status_mib(pid), base), flush=True)
    finally:
        await work.close()


def distinct_characters(count: int) -> str:
    """``count`` different characters of the hanzi store (a kiosk's public, none repeated)."""
    from planner.glyphs.hanzi import hanzi_characters

    return "".join(sorted(hanzi_characters())[DISTINCT_FROM : DISTINCT_FROM + count])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=40, help="jobs after the warm-up (40)")
    parser.add_argument("--corpus", default=CORPUS, help="characters, round and round")
    parser.add_argument("--distinct", type=int, default=0, help="N different characters")
    parser.add_argument("--trace", type=int, default=0, help="tracemalloc from this job (off)")
    parser.add_argument("--process", action="store_true", help="a real worker process")
    args = parser.parse_args()
    corpus = args.corpus
    if args.distinct:
        corpus, args.jobs = distinct_characters(args.distinct), args.distinct
    with tempfile.TemporaryDirectory() as tmp:
        if args.process:
            asyncio.run(in_a_worker_process(args, corpus, Path(tmp)))
        else:
            in_this_process(args, corpus, Path(tmp))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

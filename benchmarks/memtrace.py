"""Run a Python module under tracemalloc and write what grew, every so often, to a file.

    python benchmarks/memtrace.py OUT.txt PERIOD_S -m cli.main orchestrator show.yaml

``bench_soak.py --trace-memory DIR`` starts the orchestrator and the agents this way. The first
snapshot is taken after ``PERIOD_S`` (past start-up); each later one is compared with it, and
the allocation sites that grew most (by line, 8 frames deep for the tracebacks) replace the
file's contents: what a process keeps per job shows up as a site that grows with every period.
"""

from __future__ import annotations

import linecache
import runpy
import sys
import threading
import time
import tracemalloc
from pathlib import Path

TOP = 25
"""Allocation sites written per report."""
FRAMES = 8
"""Frames kept per allocation (tracebacks of the top sites)."""


def _snapshot() -> tracemalloc.Snapshot:
    """The process's allocations, without the tracer's own (its reports and line cache)."""
    mine = (__file__, tracemalloc.__file__, linecache.__file__)
    return tracemalloc.take_snapshot().filter_traces(
        [tracemalloc.Filter(False, path, all_frames=True) for path in mine]
    )


def _report(out: Path, period_s: float) -> None:
    time.sleep(period_s)
    first = _snapshot()
    started = time.monotonic()
    while True:
        time.sleep(period_s)
        snapshot = _snapshot()
        grown = snapshot.compare_to(first, "traceback")[:TOP]
        lines = [
            f"{time.monotonic() - started:.0f} s after the first snapshot;"
            f" traced now {tracemalloc.get_traced_memory()[0] / 2**20:.1f} MiB",
        ]
        for stat in grown:
            lines.append(f"{stat.size_diff / 1024:+10.1f} KiB {stat.count_diff:+7d} blocks")
            lines += [f"      {line}" for line in stat.traceback.format()[-2 * FRAMES :]]
        out.write_text("\n".join(lines) + "\n")


def main() -> None:
    out, period_s, flag, module, *rest = sys.argv[1:]
    if flag != "-m":
        raise SystemExit(__doc__)
    tracemalloc.start(FRAMES)
    threading.Thread(target=_report, args=(Path(out), float(period_s)), daemon=True).start()
    sys.argv = [module, *rest]
    runpy.run_module(module, run_name="__main__", alter_sys=True)


if __name__ == "__main__":
    main()

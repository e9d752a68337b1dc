"""``benchmarks/bench_memory.py``'s slopes: a process that fills a bounded history and then
stays flat grows over the run but not in its second half (the orchestrator's question of
issue 35); its figure is drawn."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from module_by_path import load_module

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


@pytest.fixture(scope="module")
def bench_memory():  # type: ignore[no-untyped-def]
    sys.path.insert(0, str(BENCHMARKS))  # its siblings (bench_show, bench_soak)
    try:
        return load_module("bench_memory", BENCHMARKS / "bench_memory.py")
    finally:
        sys.path.remove(str(BENCHMARKS))


def _filled_then_flat(bench_memory, minutes: int):  # type: ignore[no-untyped-def]
    """An orchestrator growing 1 MiB a minute for the first third, then flat; a router flat."""
    series = bench_memory.Series()
    for minute in range(minutes + 1):
        t_s = 60.0 * minute
        series.load_1min.append(1.0)
        grown_kib = 1024 * min(minute, minutes // 3)
        for name, kib in (("orchestrator", 200 * 1024 + grown_kib), ("router", 100 * 1024)):
            for measure in bench_memory.MEASURES:
                series.points.setdefault((name, measure), []).append((t_s, kib))
        for total in bench_memory.TOTALS:
            for measure in bench_memory.MEASURES:
                series.points.setdefault((total, measure), []).append((t_s, 300 * 1024 + grown_kib))
    return series


def test_the_second_half_shows_a_history_that_stopped_growing(bench_memory, capsys, tmp_path):  # type: ignore[no-untyped-def]
    series = _filled_then_flat(bench_memory, minutes=60)
    points = series.points[("orchestrator", "rss")]
    overall = bench_memory.slope_mib_per_h(points, 120.0)
    assert overall > 10.0  # over the run: growing
    assert bench_memory.late_s(series, 120.0) == pytest.approx(1860.0)
    assert bench_memory.slope_mib_per_h(points, bench_memory.late_s(series, 120.0)) == 0.0
    bench_memory.report(series, 120.0)
    bench_memory.verdict(series, 120.0)
    printed = capsys.readouterr().out
    orchestrator = next(line for line in printed.splitlines() if "orchestrator" in line)
    assert orchestrator.split()[4:6] == [
        f"{bench_memory.slope_mib_per_h(points, 120.0):+.1f}",
        "+0.0",
    ]
    assert "(second half +0 MiB/h)" in printed
    png = tmp_path / "memory.png"
    bench_memory.figure(series, png)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"

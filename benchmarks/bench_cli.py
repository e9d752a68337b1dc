"""``skyquill plan --text 永`` wall time, and the indexed glyph store beside the old whole file.

    .venv/bin/python benchmarks/bench_cli.py [--runs 5] [--text 永]

Glyphs (in this process, page cache warm for both): the indexed store
(``planner/glyphs/data/hanzi_medians.bin``; open = header and index, then one record) beside the
old whole-file decode (the same medians as the former gzipped JSON, rebuilt here byte for byte by
the former encoder, then ``gzip`` + ``json`` decoded as the former loader did on every call).
"Cold" is the first character in a fresh store, "warm" a further character from the open store;
every GB2312 level-1 character is looked up.

CLI (fresh interpreters): the wall and CPU time of ``python -m cli.main plan --text 永``, the
first run ("cold") and the median of the others ("warm"), beside the interpreter alone and the
imports the planner needs, measured in the same run: ``scipy.optimize`` (no longer imported by
the plan), ``scipy.sparse`` and ``scipy.linalg`` (still are: PIQP's sparse interface and the
banded LAPACK solves) and ``planner.pipeline``.
"""

from __future__ import annotations

import argparse
import gzip
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from planner.glyphs.hanzi import STORE_PATH  # noqa: E402
from planner.glyphs.hanzi_store import HanziStore  # noqa: E402


def gb2312_level1() -> list[str]:
    """The 3,755 characters of GB2312 level 1 (rows 16-55)."""
    chars = []
    for hi in range(0xB0, 0xD8):
        for lo in range(0xA1, 0xFF if hi < 0xD7 else 0xFA):
            chars.append(bytes([hi, lo]).decode("gb2312"))
    return chars


def old_file_bytes(store: HanziStore) -> bytes:
    """The former ``hanzi_medians.json.gz``: delta-encoded JSON, gzip level 9, mtime 0."""
    chars: dict[str, list[list[int]]] = {}
    for char in sorted(store.characters()):
        prev_x, prev_y, strokes = 0, 0, []
        for points in store.strokes(char) or []:
            flat: list[int] = []
            for x, y in points:
                flat += [x - prev_x, y - prev_y]
                prev_x, prev_y = x, y
            strokes.append(flat)
        chars[char] = strokes
    doc = {"format": "skyquill-hanzi-medians", "version": 1, **store.meta, "chars": chars}
    text = json.dumps(doc, ensure_ascii=False, separators=(",", ":"))
    return gzip.compress(text.encode("utf-8"), compresslevel=9, mtime=0)


def _ms(seconds: float) -> str:
    return f"{seconds * 1e3:8.2f} ms"


def bench_glyphs(text: str, repeats: int) -> None:
    if HanziStore(STORE_PATH).strokes(text[0]) is None:
        print(f"glyph store: {text[0]!r} is not a Chinese character, skipped")
        return
    level1 = gb2312_level1()
    old_bytes = old_file_bytes(HanziStore(STORE_PATH))
    new_cold, old_cold = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        HanziStore(STORE_PATH).strokes(text[0])
        new_cold.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        json.loads(gzip.decompress(old_bytes))["chars"][text[0]]
        old_cold.append(time.perf_counter() - t0)
    store = HanziStore(STORE_PATH)
    t0 = time.perf_counter()
    missing = [c for c in level1 if store.strokes(c) is None]
    new_warm = (time.perf_counter() - t0) / len(level1)
    print(f"glyph store: {STORE_PATH.stat().st_size / 1e6:.2f} MB on disk, {len(store)} characters")
    print(f"  old whole file: {len(old_bytes) / 1e6:.2f} MB (rebuilt in this run)")
    print(f"  first character, median of {repeats}:")
    print(f"    indexed store (index + 1 record) {_ms(statistics.median(new_cold))}")
    print(f"    old whole-file decode            {_ms(statistics.median(old_cold))}")
    print(f"  further character (indexed store)  {_ms(new_warm)}  (mean over GB2312 level 1)")
    print(f"  GB2312 level 1: {len(level1) - len(missing)}/{len(level1)} resolve")


def _run(argv: list[str]) -> tuple[float, float]:
    """Wall and CPU (user + sys) seconds of one child run from the repository root."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    before = os.times()
    t0 = time.perf_counter()
    subprocess.run(argv, cwd=ROOT, env=env, check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    after = os.times()
    cpu = (after.children_user - before.children_user) + (
        after.children_system - before.children_system
    )
    return wall, cpu


def bench_cli(text: str, runs: int) -> None:
    py = sys.executable
    cases = {
        f"skyquill plan --text {text}": [py, "-m", "cli.main", "plan", "--text", text],
        "peer: python -c pass": [py, "-c", "pass"],
        "peer: import numpy": [py, "-c", "import numpy"],
        "peer: import scipy.optimize": [py, "-c", "import scipy.optimize"],
        "peer: import scipy.sparse, .linalg": [py, "-c", "import scipy.sparse, scipy.linalg"],
        "peer: import planner.pipeline": [py, "-c", "import planner.pipeline"],
    }
    print(f"CLI, fresh interpreters, {runs} runs each (wall / CPU user+sys):")
    for label, argv in cases.items():
        results = [_run(argv) for _ in range(runs)]
        cold, warm = results[0], results[1:] or results
        warm_wall = statistics.median(w for w, _ in warm)
        warm_cpu = statistics.median(c for _, c in warm)
        print(
            f"  {label:34s} cold {cold[0]:5.2f} / {cold[1]:5.2f} s"
            f"   warm {warm_wall:5.2f} / {warm_cpu:5.2f} s"
        )
    print(f"  load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=5, help="CLI runs per case (5)")
    parser.add_argument("--text", default="永", help="text to plan (永)")
    args = parser.parse_args()
    bench_glyphs(args.text, repeats=5)
    bench_cli(args.text, max(1, args.runs))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

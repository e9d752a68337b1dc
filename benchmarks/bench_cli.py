"""One-off commands' wall time: ``skyquill plan --text 永`` and ``skyquill status``; the indexed
glyph store beside the old whole file.

    .venv/bin/python benchmarks/bench_cli.py [--runs 7] [--text 永 A ...] [--no-status] [--imports]

Glyphs (in this process, page cache warm for both): the indexed store
(``planner/glyphs/data/hanzi_medians.bin``; open = header and index, then one record) beside the
old whole-file decode (the same medians as the former gzipped JSON, rebuilt here byte for byte by
the former encoder, then ``gzip`` + ``json`` decoded as the former loader did on every call).
"Cold" is the first character in a fresh store, "warm" a further character from the open store;
every GB2312 level-1 character is looked up.

CLI (fresh interpreters): the wall and CPU time of ``python -m cli.main plan --text T`` for each
``--text`` and of ``python -m cli.main status SHOW`` against a show this script runs (its own
router and orchestrator, mutual TLS, keys made for it), the first run ("cold") and the median and
least of the others ("warm"), every case with one OpenBLAS thread (as ``plan`` asks), beside peers
run in turn with the commands (a change of load on a shared machine falls on every case): the
interpreter alone, and the imports each command cannot do without (``numpy`` + ``piqp``: the
arrays and the QP solver, as a plan imports no SciPy, with ``numpy`` alone beside it: a plan at
a fixed total time whose closed form meets the limits loads no PIQP, a default plan always does
for its time law, planner.time_law; ``yaml`` + ``zenoh`` +
``msgspec``: the show file, the bus and its messages); the ratio is each command's warm wall
time to that peer's. Each case runs twice: with the environment's bytecode setting (sessions here
have ``PYTHONDONTWRITEBYTECODE=1``: every project module is compiled on every run) and with
bytecode cached (``PYTHONPYCACHEPREFIX`` in a temporary folder, written by the first run), as an
installed ``skyquill`` has it.
``--imports`` prints what each command imports, grouped, from ``python -X importtime``, which
leaves out the modules imported by ``importlib.import_module`` (the subcommand's ``cli/cmd_*.py``,
the kind's module) and lists only what they import.

Where ``plan``'s time goes beyond the peer (2026-11-30, 永, bytecode cached; instructions counted by
``valgrind --tool=callgrind``, which no load on this shared machine changes; at about 0.2 ms per
million): the peer ``import numpy, piqp`` 404 M (numpy alone 397 M, the interpreter alone 90 M), the
plan 656 M: 1.62 times the peer's (798 M, 1.97 times, before issue 35: the brush's plan loaded the
kinds' interface and its flight settings, the controller and simulated world, and PIQP though it
solved no QP). Beyond numpy: argparse and the command's module (``json``, ``dataclasses``, the
limits, the kinds' records) 32 M, building and reading the parser (argparse loads ``shutil`` and
``locale`` there) 15 M, the glyph and its store 16 M, the brush's planning module, the surface and
the summary 9 M, the planner's modules 114 M (``planner.trajectory`` and what it imports 30 M,
``planner.fit_qp`` 42 M, the rest of ``planner.pipeline`` 42 M), the plan and its summary 75 M. The
26 dataclasses built (about 4 M each: ``dataclasses`` compiles six methods of a frozen one from
source) are about 107 M of it; 4 of them these plans never make (``QpData``, ``QpSolution``,
``PreparedPlan``, ``LatinChar``). Garbage collection: 16 M (the peer 14 M); the teardown: 39 M (the
peer 33 M). ``cli/main.py`` no longer imports ``logging`` (6 ms for every command). The editable
install's path finder (``.pth``) costs every interpreter 11 ms, the peer's included.
2026-12-02 (callgrind, bytecode cached): the peer 401 M; the plan of 永 713 M with the time law
(planner.time_law: its QP on PIQP's dense interface, 3.6 ms), 674 M (1.68 times) once argparse's
help width no longer imports ``shutil`` (with ``bz2`` and ``lzma``), the OpenBLAS file is found
without ``glob``, the planner's array records skip their generated ``__eq__`` and the flight is
measured once; A 800 -> 775 M. 1.3 times the peer would be 521 M: less than the plan's own
imports and its work leave (the planner's 21 frozen dataclasses alone about 7 ms).

Figures (2026-11-26, shared 2-core machine, warm median / least wall). Plan, at load 1.0-1.4 (7
runs): 永 0.55 / 0.36 s with bytecode not written, 0.39 / 0.29 s cached; A 0.56 / 0.40 and 0.42 /
0.33 s; 国 0.59 / 0.41 and 0.42 / 0.33 s; the peer ``import numpy, piqp`` 0.24 / 0.20 and 0.21 /
0.16 s (other work shared the cores: a run beside it took about 1.5 times as long as a run alone,
hence the gap between median and least). Issue 15's SciPy work (QPs on PIQP's dense interface, band
solves in numpy, no flight code loaded), interleaved with the former code (15 runs, load 1.1-1.4,
bytecode not written): 永 0.94 / 0.71 -> 0.54 / 0.36 s, A 0.93 / 0.74 -> 0.50 / 0.36 s, 国 0.87 /
0.67 -> 0.52 / 0.40 s. What the plan imports now (``-X importtime`` self time, bytecode not
written, median of 3): planner 93 ms, numpy 72 ms, the standard library 65 ms, vehicles 49 ms, piqp
4 ms; the plan itself then takes 80-100 ms, 13 ms of it PIQP's dense solve. Before, scipy.sparse
(176 ms of CPU, most of it numpy's submodules pulled in by SciPy's vendored array-api-compat) and
scipy.linalg (57 ms) came on top. Status, as measured before (load 2.3-2.6, 9 runs): 0.24 / 0.22 s
not written, 0.22 / 0.17 s cached (peer ``import yaml, zenoh, msgspec`` 0.14 / 0.11 s). Before
issue 15's first import work (11 runs, load 2.4, bytecode not written): plan 1.07 -> 0.85 s, status
0.84 -> 0.25 s.
"""

from __future__ import annotations

import argparse
import contextlib
import gzip
import json
import os
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import yaml

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


def _run(argv: list[str], env: dict[str, str]) -> tuple[float, float]:
    """Wall and CPU (user + sys) seconds of one child run from the repository root."""
    before = os.times()
    t0 = time.perf_counter()
    subprocess.run(argv, cwd=ROOT, env=env, check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    after = os.times()
    cpu = (after.children_user - before.children_user) + (
        after.children_system - before.children_system
    )
    return wall, cpu


def _envs(cache_dir: Path) -> dict[str, dict[str, str]]:
    """The environment as it is, and with bytecode cached in ``cache_dir``; one OpenBLAS thread
    for every case, as ``skyquill plan`` asks itself, so that its peers pay no more for it."""
    as_is = {**os.environ, "PYTHONPATH": str(ROOT), "OPENBLAS_NUM_THREADS": "1"}
    cached = {k: v for k, v in as_is.items() if k != "PYTHONDONTWRITEBYTECODE"}
    cached["PYTHONPYCACHEPREFIX"] = str(cache_dir)
    bytecode = "not written" if os.environ.get("PYTHONDONTWRITEBYTECODE") else "as usual"
    return {f"environment (bytecode {bytecode})": as_is, "bytecode cached": cached}


def bench_commands(cases: dict[str, list[str]], peer: str, runs: int) -> None:
    """Each case in both environments: cold, warm median (wall / CPU) and, for each command
    (the cases not named ``peer: ...``), its ratio to ``peer``."""
    with tempfile.TemporaryDirectory(prefix="bench_cli_pyc_") as cache_dir:
        for env_label, env in _envs(Path(cache_dir)).items():
            if "PYTHONPYCACHEPREFIX" in env:
                for argv in cases.values():  # writes the cache; not counted
                    _run(argv, env)
            print(f"  {env_label}, {runs} runs each (wall / CPU user+sys; warm: median, min):")
            results: dict[str, list[tuple[float, float]]] = {label: [] for label in cases}
            for _ in range(runs):  # interleaved: a change of load on this machine hits every case
                for label, argv in cases.items():
                    results[label].append(_run(argv, env))
            warm_walls = {}
            for label, timings in results.items():
                cold, warm = timings[0], timings[1:] or timings
                warm_walls[label] = statistics.median(w for w, _ in warm)
                warm_cpu = statistics.median(c for _, c in warm)
                least = min(warm)
                print(
                    f"    {label:40s} cold {cold[0]:5.2f} / {cold[1]:5.2f} s"
                    f"   warm {warm_walls[label]:5.2f} / {warm_cpu:5.2f} s,"
                    f" min {least[0]:5.2f} / {least[1]:5.2f} s"
                )
            for command in (label for label in cases if not label.startswith("peer:")):
                ratio = warm_walls[command] / warm_walls[peer]
                print(f"    ratio {command} / {peer}: {ratio:.2f}")
    print(f"  load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")


PLAN_PEER = "peer: import numpy, piqp"
"""What ``skyquill plan`` cannot do without: numpy and the QP solver."""


def plan_cases(texts: list[str]) -> dict[str, list[str]]:
    py = sys.executable
    plans = {
        f"skyquill plan --text {t}": [py, "-m", "cli.main", "plan", "--text", t] for t in texts
    }
    return {
        **plans,
        "peer: python -c pass": [py, "-c", "pass"],
        "peer: import numpy": [py, "-c", "import numpy"],
        PLAN_PEER: [py, "-c", "import numpy, piqp"],
        "peer: import planner.pipeline": [py, "-c", "import planner.pipeline"],
    }


def status_cases(show: Path) -> dict[str, list[str]]:
    py = sys.executable
    return {
        "skyquill status (mTLS, orchestrator up)": [py, "-m", "cli.main", "status", str(show)],
        "peer: python -c pass": [py, "-c", "pass"],
        "peer: import yaml, zenoh, msgspec": [py, "-c", "import yaml, zenoh, msgspec"],
    }


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


@contextlib.contextmanager
def running_show(folder: Path) -> Iterator[Path]:
    """A one-vehicle show (solo.yaml's fleet) with its router and orchestrator running, on a
    free port, keys and state in ``folder``; stopped on exit."""
    doc = yaml.safe_load((ROOT / "shows" / "solo.yaml").read_text(encoding="utf-8"))
    endpoint = f"tcp/127.0.0.1:{_free_port()}"
    doc.update(
        show_id="clibench",
        zenoh={"router_listen": [endpoint], "connect": [endpoint]},
        security={"mode": "mtls", "keys_dir": str(folder / "keys")},
        storage={"database": str(folder / "show.sqlite3"), "recordings_dir": str(folder / "rec")},
    )
    show = folder / "show.yaml"
    show.write_text(yaml.safe_dump(doc), encoding="utf-8")
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    cli = [sys.executable, "-m", "cli.main"]
    subprocess.run([*cli, "keys", str(show)], cwd=ROOT, env=env, check=True, capture_output=True)
    services = []
    try:
        for command in ("router", "orchestrator"):
            with (folder / f"{command}.log").open("w") as log:  # the child keeps its own copy
                services.append(
                    subprocess.Popen([*cli, command, str(show)], cwd=ROOT, env=env, stderr=log)
                )
        status = [*cli, "status", str(show), "--timeout", "1"]
        deadline = time.monotonic() + 60.0
        while subprocess.run(status, cwd=ROOT, env=env, capture_output=True).returncode != 0:
            if time.monotonic() > deadline:
                raise RuntimeError(f"the show did not answer in 60 s (logs in {folder})")
            time.sleep(0.5)
        yield show
    finally:
        for service in reversed(services):
            service.terminate()
            try:
                service.wait(timeout=10.0)
            except subprocess.TimeoutExpired:
                service.kill()
                service.wait()


def _import_groups(argv: list[str]) -> list[tuple[str, float]]:
    """Self import time in [s] of ``argv``'s modules, by package (scipy and numpy by
    subpackage), from one run with ``-X importtime``."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    run = subprocess.run(
        [argv[0], "-X", "importtime", *argv[1:]], cwd=ROOT, env=env, capture_output=True, text=True
    )
    groups: dict[str, float] = {}
    for line in run.stderr.splitlines():
        if not line.startswith("import time:") or "self [us]" in line:
            continue
        self_us, _, name = (part.strip() for part in line.removeprefix("import time:").split("|"))
        parts = name.split(".")
        key = ".".join(parts[:2]) if parts[0] in ("numpy", "scipy") else parts[0]
        groups[key] = groups.get(key, 0.0) + int(self_us) * 1e-6
    return sorted(groups.items(), key=lambda item: -item[1])


def print_imports(label: str, argv: list[str], top: int = 14) -> None:
    groups = _import_groups(argv)
    total = sum(seconds for _, seconds in groups)
    print(f"  {label}: imports {total * 1e3:.0f} ms (self time, -X importtime), largest:")
    for name, seconds in groups[:top]:
        print(f"    {name:28s} {seconds * 1e3:6.1f} ms")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=7, help="CLI runs per case (7)")
    parser.add_argument(
        "--text", nargs="+", default=["永"], help="texts to plan, one command each (永)"
    )
    parser.add_argument("--no-status", action="store_true", help="skip skyquill status")
    parser.add_argument("--imports", action="store_true", help="print each command's imports")
    args = parser.parse_args()
    runs = max(2, args.runs)
    bench_glyphs(args.text[0], repeats=5)
    plan = plan_cases(args.text)
    print("CLI plan, fresh interpreters:")
    bench_commands(plan, PLAN_PEER, runs)
    if args.imports:
        print_imports(next(iter(plan)), next(iter(plan.values())))
    if args.no_status:
        return 0
    with (
        tempfile.TemporaryDirectory(prefix="bench_cli_show_") as folder,
        running_show(Path(folder)) as show,
    ):
        status = status_cases(show)
        print("CLI status, fresh interpreters:")
        bench_commands(status, "peer: import yaml, zenoh, msgspec", runs)
        if args.imports:
            print_imports(next(iter(status)), next(iter(status.values())))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

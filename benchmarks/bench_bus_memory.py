"""Bus memory under hostile sizes: does a flood of large submissions leave memory behind?

    .venv/bin/python benchmarks/bench_bus_memory.py [--messages 6000] [--every 500] [--png F]
    .venv/bin/python benchmarks/bench_bus_memory.py --before DIR   # DIR: the code before the fix

Starts the show's real router and orchestrator (``skyquill router`` / ``skyquill orchestrator``
on a copy of ``shows/solo.yaml`` on a free loopback port, mutual TLS as every show) and floods
them from a client of this process (the ``operator`` identity, on the plain submit key),
``--in-flight`` submissions at a time. Each is a strokes document with one stroke more than a
document may hold, so the orchestrator decodes it whole, records it and refuses it
(``invalid_strokes``): no job is made. Every ``--every`` messages it reads the resident set
(``VmRSS``) of the router and of the orchestrator from ``/proc``, and the part of it that is
shared memory (``RssShmem``: Zenoh's shared-memory pools).

Two series, each with fresh processes: messages at the request limit (``bus.codec``; sizes drawn
from 90-100 % of it), and, as the peer in the same run, small messages (the same document with
one point a stroke, 3.3 kB). ``--before DIR`` runs the router and the orchestrator from DIR, a
copy of the tree with ``bus/codec.py``, ``bus/rpc.py`` and ``bus/session.py`` as they were
before the fix (the show file must load there), with messages of 0.9-1.0 MB, the limit of then,
and the flooding client with Zenoh's defaults for size. Printed: each series' curve, its growth
from start to end, and per message over the second half (near 0: the process levelled off); the
load (``uptime``) at start and end. About 8 minutes (``--before``: 20) on two busy cores.
"""

from __future__ import annotations

import argparse
import asyncio
import random
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bus.codec import MAX_REQUEST_BYTES, encode  # noqa: E402
from bus.keys import ShowKeys  # noqa: E402
from bus.messages import ShowSnapshot, SubmitReply, SubmitRequest  # noqa: E402
from bus.rpc import QueryReply, aquery, query  # noqa: E402
from bus.session import Session, open_session  # noqa: E402
from cli.showrun import derived_show  # noqa: E402
from planner.glyphs import MAX_STROKES  # noqa: E402
from trust.settings import ensure_show_keys, session_settings  # noqa: E402

SHOW = ROOT / "shows" / "solo.yaml"
MIB = 1024.0 * 1024.0
BEFORE_BYTES = 1_000_000
"""The payload limit before the fix (every request)."""
SIZES = 8
"""Distinct message sizes a series draws from (90-100 % of its largest)."""
ZENOH_DEFAULTS = {
    "transport/shared_memory/enabled": True,
    "transport/link/rx/max_message_size": 1 << 30,
}
"""What ``bus.session`` sets for size, back at Zenoh's defaults: the flooding client's
configuration with ``--before``, as the processes under test have it there."""


def strokes_request(size_bytes: int) -> SubmitRequest:
    """A submission of at most ``size_bytes`` encoded (at least its smallest form): one stroke
    more than a document may hold, as many points each as fit."""

    def request(points: int) -> SubmitRequest:
        stroke = [[100.0 + 0.25 * i, 200.0 + 0.5 * (i % 97)] for i in range(points)]
        doc = {"units": "px", "y_axis": "down", "strokes": [stroke] * (MAX_STROKES + 1)}
        return SubmitRequest(strokes=doc, client_id="flood")

    per_point = len(encode(request(101))) - len(encode(request(100)))
    points = max(1, (size_bytes - len(encode(request(1)))) // per_point)
    while points > 1 and len(encode(request(points))) > size_bytes:
        points -= 1
    return request(points)


def memory_mib(pid: int) -> tuple[float, float]:
    """Resident set of ``pid`` and its shared-memory part (``VmRSS``, ``RssShmem``), in MiB."""
    fields = {}
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        name, _, value = line.partition(":")
        if name in ("VmRSS", "RssShmem"):
            fields[name] = int(value.split()[0]) * 1024 / MIB
    return fields["VmRSS"], fields["RssShmem"]


def load() -> str:
    """The load averages, as ``uptime`` gives them."""
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


@dataclass
class Series:
    name: str
    sizes: list[int]
    """Encoded bytes of the messages it draws from."""
    counts: list[int] = field(default_factory=list)
    router: list[tuple[float, float]] = field(default_factory=list)
    """(RSS, shared memory) in MiB at each count."""
    orchestrator: list[tuple[float, float]] = field(default_factory=list)
    codes: dict[str, int] = field(default_factory=dict)


def _child(root: Path, args: list[str], log: Path) -> subprocess.Popen[bytes]:
    with log.open("wb") as out:
        return subprocess.Popen(
            [sys.executable, "-m", "cli.main", *args], cwd=root, stdout=out, stderr=out
        )


def _code(reply: QueryReply[SubmitReply]) -> str:
    """The reply's error code, or ``ok``."""
    error = reply.error or (reply.value.error if reply.value is not None else None)
    return "ok" if error is None else error.code


async def _flood(
    session: Session,
    key: str,
    payloads: list[bytes],
    args: argparse.Namespace,
    sample: Series,
    pids: tuple[int, int],
) -> None:
    rng = random.Random(1)
    in_flight = asyncio.Semaphore(args.in_flight)

    async def one(payload: bytes) -> None:
        async with in_flight:
            replies = await aquery(session, key, payload, SubmitReply, timeout_s=30.0)
        codes = [_code(reply) for reply in replies] or ["no_reply"]
        for code in codes:
            sample.codes[code] = sample.codes.get(code, 0) + 1

    for start in range(0, args.messages + 1, args.every):
        sample.counts.append(start)
        sample.router.append(memory_mib(pids[0]))
        sample.orchestrator.append(memory_mib(pids[1]))
        batch = min(args.every, args.messages - start)
        await asyncio.gather(*(one(rng.choice(payloads)) for _ in range(batch)))


def run_series(name: str, largest: int, root: Path, args: argparse.Namespace) -> Series:
    fractions = [0.9 + 0.1 * k / (SIZES - 1) for k in range(SIZES)]
    payloads = [encode(strokes_request(int(largest * f))) for f in fractions]
    series = Series(name, sorted({len(p) for p in payloads}))
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        path, show = derived_show(SHOW, out)
        ensure_show_keys(show)
        keys = ShowKeys(show.show_id)
        router = _child(root, ["router", str(path)], out / "router.log")
        orchestrator = _child(root, ["orchestrator", str(path)], out / "orchestrator.log")
        try:
            settings = session_settings(show, "operator")
            if args.before:
                settings = replace(settings, extra={**settings.extra, **ZENOH_DEFAULTS})
            with open_session(settings, role="client", open_timeout_s=20) as client:
                deadline = time.monotonic() + 60
                while not query(client, keys.snapshot, None, ShowSnapshot, timeout_s=1.0):
                    if time.monotonic() > deadline:
                        raise SystemExit("the orchestrator did not answer")
                time.sleep(1.0)  # past start-up
                pids = (router.pid, orchestrator.pid)
                asyncio.run(_flood(client, keys.submit, payloads, args, series, pids))
        finally:
            for child in (orchestrator, router):
                child.terminate()
                child.wait(30)
    return series


def report(series: Series) -> None:
    codes = ", ".join(f"{n} {c}" for c, n in sorted(series.codes.items()))
    low, high = series.sizes[0], series.sizes[-1]
    print(f"\n{series.name}: messages of {low}-{high} bytes; replies: {codes}")
    print(f"  {'messages':>8}  {'router MiB (shm)':>17}  {'orchestrator MiB (shm)':>23}")
    for count, (r, r_shm), (o, o_shm) in zip(
        series.counts, series.router, series.orchestrator, strict=True
    ):
        print(f"  {count:8d}  {r:9.1f} ({r_shm:5.1f})  {o:15.1f} ({o_shm:5.1f})")
    half = len(series.counts) // 2
    span = series.counts[-1] - series.counts[half]
    for label, values in (("router", series.router), ("orchestrator", series.orchestrator)):
        first, last = values[0][0], values[-1][0]
        per_message_kib = (last - values[half][0]) * 1024 / span if span else 0.0
        print(
            f"  {label}: {first:.1f} -> {last:.1f} MiB ({last - first:+.1f} MiB),"
            f" second half {per_message_kib:+.2f} KiB/message"
        )


def figure(all_series: list[Series], path: Path) -> None:
    """RSS against messages sent, the router and the orchestrator side by side."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), sharey=True)
    for ax, process in zip(axes, ("router", "orchestrator"), strict=True):
        for series in all_series:
            values = [rss for rss, _ in getattr(series, process)]
            label = f"{series.name} ({series.sizes[-1] / 1000:.0f} kB)"
            ax.plot(series.counts, values, marker="o", markersize=3, label=label)
        ax.set_title(process)
        ax.set_xlabel("messages sent")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("RSS [MiB]")
    axes[0].legend(fontsize=8)
    fig.suptitle("Resident memory under a flood of submissions")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--messages", type=int, default=6000, help="per series (6000)")
    parser.add_argument("--every", type=int, default=500, help="messages between samples (500)")
    parser.add_argument("--in-flight", type=int, default=4, help="queries at a time (4)")
    parser.add_argument("--png", type=Path, default=Path("bench_bus_memory.png"))
    parser.add_argument(
        "--before",
        type=Path,
        metavar="DIR",
        help="run the router and the orchestrator from DIR, with messages at the limit of then",
    )
    args = parser.parse_args()
    root = (args.before or ROOT).resolve()
    print(f"load at start: {load()}")
    plan = [("at the limit", BEFORE_BYTES if args.before else MAX_REQUEST_BYTES), ("small", 0)]
    done = []
    for name, largest in plan:
        done.append(run_series(name, largest, root, args))
        report(done[-1])
    print(f"\nload at end: {load()}")
    figure(done, args.png)
    print(f"figure: {args.png}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

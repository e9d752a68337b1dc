"""A SITL show run the way the README runs it: ``scripts/sitl/start.py SHOW``, ``skyquill up
--headless SHOW``, ``skyquill submit SHOW --text X``, then what was written, from ``skyquill
status --json`` and ``skyquill log --json``. Used by ``bench_sitl_show.py`` and the SITL show
tests (``tests/test_sitl_show.py``).

The show file is copied into a fresh folder with only its storage moved there (its database,
recordings and keys; the copy's relative paths start from the copy), so every run starts with new
vehicles: no tracking identified yet, an empty queue. Everything else is the show as written.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

ROOT = Path(__file__).resolve().parents[1]
SKYQUILL = [sys.executable, "-m", "cli.main"]
TERMINAL = ("done", "failed", "cancelled", "rejected")
READY_LIMIT_S = 420.0
"""Longest wait for start.py to say every instance is ready (four ArduCopters booting at once on
two cores: each EKF about 40 s alone)."""


class ShowRunError(RuntimeError):
    """The show did not start, or a job did not end in time; the message says which."""


@dataclass
class ShowRun:
    """A running SITL show and its folder."""

    show_path: Path
    folder: Path
    processes: list[subprocess.Popen[bytes]] = field(default_factory=list)
    loads: list[float] = field(default_factory=list)
    """The machine's 1-minute load average at each poll while jobs were awaited."""
    swaps: list[str] = field(default_factory=list)
    """Vehicles whose battery the bench's crew swapped, in order (it confirms at its next poll:
    the SITL's reset, MAV_CMD_BATTERY_RESET or PX4's full pack when disarmed, is the swap)."""
    _swapping: set[str] = field(default_factory=set)

    def skyquill(self, *args: str, timeout_s: float = 30.0) -> str:
        """Run ``skyquill ARGS`` (the show file appended) and return its output; ShowRunError
        with its stderr when it fails."""
        done = subprocess.run(
            [*SKYQUILL, *args, str(self.show_path)],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=timeout_s,
        )
        if done.returncode != 0:
            raise ShowRunError(f"skyquill {args[0]}: {done.stderr.strip()}")
        return done.stdout

    def submit(self, text: str) -> str:
        """Submit ``text``; its job id."""
        out = self.skyquill("submit", "--text", text)  # "submitted (queued, ...) job ID"
        return out.strip().rpartition(" job ")[2]

    def status(self) -> dict[str, Any]:
        data: dict[str, Any] = json.loads(self.skyquill("status", "--json"))
        return data

    def events(self) -> list[dict[str, Any]]:
        lines = self.skyquill("log", "--json").splitlines()
        return [json.loads(line) for line in lines if line.strip()]

    def wait_jobs(self, count: int, limit_s: float) -> list[dict[str, Any]]:
        """Wait until ``count`` jobs have ended; the jobs as ``status --json`` gives them."""
        deadline = time.monotonic() + limit_s
        while True:
            self.check_alive()
            self.loads.append(os.getloadavg()[0])
            status = self.status()
            self._crew(status["vehicles"])
            jobs = status["jobs"]
            ended = [j for j in jobs if j["state"] in TERMINAL]
            if len(ended) >= count:
                return jobs
            if time.monotonic() > deadline:
                states = sorted(j["state"] for j in jobs)
                raise ShowRunError(
                    f"{len(ended)} of {count} jobs ended in {limit_s:.0f} s: {states}"
                )
            time.sleep(5.0)

    def _crew(self, vehicles: list[dict[str, Any]]) -> None:
        """Confirm a battery swap for each vehicle newly waiting for one, as the crew would."""
        waiting = {v["vehicle_id"] for v in vehicles if v["state"] == "battery_swap"}
        for vehicle_id in sorted(waiting - self._swapping):
            confirm = [*SKYQUILL, "command", str(self.show_path), "battery-swapped", vehicle_id]
            subprocess.run(confirm, cwd=ROOT, capture_output=True, timeout=30.0, check=True)
            self.swaps.append(vehicle_id)
        self._swapping = waiting

    def wait_vehicles(self, limit_s: float = 120.0) -> None:
        """Wait until the orchestrator answers and sees every vehicle alive."""
        deadline = time.monotonic() + limit_s
        last = "no answer"
        while time.monotonic() < deadline:
            self.check_alive()
            try:
                vehicles = self.status()["vehicles"]
            except (ShowRunError, subprocess.TimeoutExpired) as exc:
                last = str(exc)
            else:
                if vehicles and all(v["alive"] for v in vehicles):
                    return
                last = ", ".join(f"{v['vehicle_id']} {v['state']}" for v in vehicles)
            time.sleep(2.0)
        raise ShowRunError(f"the vehicles did not come up in {limit_s:.0f} s: {last}")

    def check_alive(self) -> None:
        for proc in self.processes:
            if proc.poll() is not None:
                raise ShowRunError(f"{proc.args!r} exited with {proc.returncode}")


def fresh_copy(show_path: Path, folder: Path) -> Path:
    """The show file copied into ``folder`` with its storage moved there."""
    doc = yaml.safe_load(show_path.read_text(encoding="utf-8"))
    doc["storage"] = {**doc.get("storage", {}), "database": "state/show.sqlite3",
                      "recordings_dir": "state/recordings"}  # fmt: skip
    doc.get("security", {}).pop("keys_dir", None)
    copy = folder / show_path.name
    copy.write_text(yaml.safe_dump(doc, sort_keys=False, allow_unicode=True), encoding="utf-8")
    return copy


def _start(argv: list[str], log: Path) -> subprocess.Popen[bytes]:
    with open(log, "wb") as out:
        return subprocess.Popen(
            argv, cwd=ROOT, stdout=out, stderr=subprocess.STDOUT, start_new_session=True
        )


def _wait_line(log: Path, proc: subprocess.Popen[bytes], text: str, limit_s: float) -> None:
    start_s = time.monotonic()
    while time.monotonic() < start_s + limit_s:
        if text in log.read_text(encoding="utf-8", errors="replace"):
            return
        if proc.poll() is not None:
            break
        time.sleep(1.0)
    tail = log.read_text(encoding="utf-8", errors="replace").splitlines()[-8:]
    waited = f"{time.monotonic() - start_s:.0f} s"
    ended = f"it exited (rc {proc.returncode}) after {waited}" if proc.poll() is not None else (
        f"not in {waited}")  # fmt: skip
    raise ShowRunError(f"{log.name}: no {text!r}, {ended}: " + " | ".join(tail))


def _stop(proc: subprocess.Popen[bytes], limit_s: float = 60.0) -> None:
    """SIGINT, as Ctrl-C would (``up`` asks while vehicles fly: a second one stops), then
    SIGTERM and SIGKILL to its process group."""
    for sig, wait_s in ((signal.SIGINT, limit_s), (signal.SIGINT, 10.0), (signal.SIGTERM, 10.0)):
        if proc.poll() is not None:
            return
        try:
            os.killpg(proc.pid, sig)
        except ProcessLookupError:
            return
        try:
            proc.wait(timeout=wait_s)
        except subprocess.TimeoutExpired:
            continue
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()


@contextmanager
def running(
    show_path: Path, folder: Path | None = None, sitl_args: tuple[str, ...] = ()
) -> Iterator[ShowRun]:
    """start.py (with ``sitl_args``) and ``skyquill up --headless`` on a fresh copy of
    ``show_path``, every vehicle up; stopped (``up`` first, then the autopilots) on leaving."""
    folder = folder or Path(tempfile.mkdtemp(prefix=f"skyquill-{show_path.stem}-"))
    copy = fresh_copy(show_path, folder)
    run = ShowRun(copy, folder)
    sitl_log, up_log = folder / "start.log", folder / "up.log"
    try:
        sitl = _start([sys.executable, str(ROOT / "scripts/sitl/start.py"), str(copy),
                       "--run-dir", str(folder / "sitl"), *sitl_args], sitl_log)  # fmt: skip
        run.processes.append(sitl)
        _wait_line(sitl_log, sitl, "all ready", READY_LIMIT_S)
        run.processes.append(_start([*SKYQUILL, "up", "--headless", str(copy)], up_log))
        run.wait_vehicles()
        yield run
    finally:
        for proc in reversed(run.processes):
            _stop(proc)

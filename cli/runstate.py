"""What a running ``skyquill up`` leaves on disk, and processes it did not start itself.

``up`` writes ``<database dir>/up.json`` (:class:`RunFile`): its own pid and each child's pid
with the kernel's start time of that process, so that a pid reused by an unrelated process is
never taken for a show process. ``skyquill down`` reads it to stop the show; a restarted ``up``
reads it to adopt the children that outlived an ``up`` that was killed (:class:`AdoptedProcess`).
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import time
from dataclasses import dataclass, field
from pathlib import Path

RUN_FILE_NAME = "up.json"


class RunFileError(ValueError):
    """The run file exists but cannot be read."""


def start_ticks(pid: int) -> int | None:
    """Start time of process ``pid`` in clock ticks since boot (None: no such live process)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    fields = stat.rsplit(")", 1)[1].split()
    if fields[0] in ("Z", "X"):  # a zombie has finished
        return None
    return int(fields[19])


def cpu_ticks(pid: int) -> int | None:
    """CPU time process ``pid`` has used so far, user and system, in clock ticks (None: gone)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    fields = stat.rsplit(")", 1)[1].split()
    return int(fields[11]) + int(fields[12])


def descendants(pid: int) -> list[int]:
    """The processes ``pid`` started and those they started, from ``/proc`` (a process stopping
    may be waiting for one: an agent for its planning worker's last picture)."""
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        parent = int(stat.rsplit(")", 1)[1].split()[1])
        children.setdefault(parent, []).append(int(entry.name))
    found, todo = [], [pid]
    while todo:
        for child in children.get(todo.pop(), ()):
            found.append(child)
            todo.append(child)
    return found


def family_cpu_ticks(pid: int) -> int | None:
    """CPU time of process ``pid`` and its descendants now running, in clock ticks (None: gone)."""
    own = cpu_ticks(pid)
    if own is None:
        return None
    return own + sum(cpu_ticks(child) or 0 for child in descendants(pid))


def family_runnable(pid: int) -> bool:
    """Whether process ``pid`` or one of its descendants is running or waiting for a CPU."""
    return any(runnable(one) for one in (pid, *descendants(pid)))


def runnable(pid: int) -> bool:
    """Whether a thread of process ``pid`` is running or waiting for a CPU (state ``R``): busy,
    even when a loaded machine gives it no CPU time for a while."""
    try:
        tasks = list(Path(f"/proc/{pid}/task").iterdir())
    except OSError:
        return False
    for task in tasks:
        try:
            stat = (task / "stat").read_text()
        except OSError:
            continue
        if stat.rsplit(")", 1)[1].split()[0] == "R":
            return True
    return False


def command_line(pid: int) -> tuple[str, ...]:
    """The argv of process ``pid`` (empty when unknown)."""
    try:
        raw = Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return ()
    return tuple(part.decode(errors="replace") for part in raw.split(b"\0") if part)


@dataclass(frozen=True)
class ProcessRecord:
    """One process as ``up`` recorded it."""

    pid: int
    """Process id."""
    ticks: int
    """Its start time in clock ticks since boot (tells it from a later process with its pid)."""

    def alive(self) -> bool:
        """Whether this very process still runs."""
        return start_ticks(self.pid) == self.ticks

    @classmethod
    def of(cls, pid: int) -> ProcessRecord | None:
        ticks = start_ticks(pid)
        return None if ticks is None else cls(pid, ticks)


@dataclass
class RunFile:
    """The show processes of one ``skyquill up``."""

    path: Path
    """Where it is kept: ``<database dir>/up.json``."""
    show_id: str
    """The show."""
    up: ProcessRecord | None = None
    """The ``skyquill up`` supervising it."""
    children: dict[str, ProcessRecord] = field(default_factory=dict)
    """Supervised children by name (``router``, ``orchestrator``, ``agent uav1``...)."""

    def save(self) -> None:
        """Write it atomically (a reader never sees half a file)."""
        data = {
            "show_id": self.show_id,
            "up": None if self.up is None else [self.up.pid, self.up.ticks],
            "children": {name: [r.pid, r.ticks] for name, r in self.children.items()},
        }
        self.path.parent.mkdir(parents=True, exist_ok=True)
        tmp = self.path.with_suffix(".tmp")
        tmp.write_text(json.dumps(data, indent=1), encoding="utf-8")
        os.replace(tmp, self.path)

    def remove(self) -> None:
        self.path.unlink(missing_ok=True)

    @classmethod
    def load(cls, path: Path) -> RunFile | None:
        """The run file at ``path`` (None when there is none)."""
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
            up = None if data["up"] is None else ProcessRecord(*data["up"])
            children = {name: ProcessRecord(*pt) for name, pt in data["children"].items()}
            return cls(path, str(data["show_id"]), up, children)
        except FileNotFoundError:
            return None
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise RunFileError(f"{path}: unreadable run file ({exc}); delete it") from exc


def run_file_path(database_path: Path, host: str | None = None) -> Path:
    """The run file of the show whose SQLite file is ``database_path`` (``up-<host>.json`` for
    one host of a show across machines)."""
    name = RUN_FILE_NAME if host is None else f"up-{host}.json"
    return Path(database_path).parent / name


class AdoptedProcess:
    """A process this supervisor did not start (a previous ``up`` did): the parts of
    ``subprocess.Popen`` the supervisor uses, through ``/proc`` and signals. Its exit status is
    unknown (its parent reaps it), so ``returncode`` becomes :data:`UNKNOWN_STATUS`."""

    UNKNOWN_STATUS = 255

    def __init__(self, record: ProcessRecord) -> None:
        self.record = record
        self.pid = record.pid
        self.returncode: int | None = None

    def poll(self) -> int | None:
        if self.returncode is None and not self.record.alive():
            self.returncode = self.UNKNOWN_STATUS
        return self.returncode

    def send_signal(self, sig: int) -> None:
        if self.poll() is None:
            with contextlib.suppress(ProcessLookupError):
                os.kill(self.pid, sig)

    def terminate(self) -> None:
        self.send_signal(signal.SIGTERM)

    def kill(self) -> None:
        self.send_signal(signal.SIGKILL)

    def wait(self, timeout: float | None = None) -> int:
        deadline = None if timeout is None else time.monotonic() + timeout
        while (status := self.poll()) is None:
            if deadline is not None and time.monotonic() >= deadline:
                raise subprocess.TimeoutExpired(f"pid {self.pid}", timeout or 0.0)
            time.sleep(0.02)
        return status

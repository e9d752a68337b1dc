"""Stopping a group of the supervisor's children: SIGTERM to each, then wait for each its own
grace, and SIGKILL only the ones that outlived it and sit idle.

The grace is measured against the child's progress: past it, a child still using CPU or waiting
for one (stopping, only slowed by the others stopping beside it on a busy machine) is given up to
its limit; one that sits idle (stuck) is killed. Fifty agents stopping at once on two cores each
need many seconds of wall time for about one of CPU. A child's own children count as its
progress: an agent waiting for its planning worker to draw a finished job's picture is stopping
(at load 23 a picture took over 8 s, and the agent waiting for it was killed as stuck).
"""

from __future__ import annotations

import signal
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import ClassVar, Protocol

from cli.runstate import AdoptedProcess, family_cpu_ticks, family_runnable


class ProcessHandle(Protocol):
    """What the supervisor needs of a process: ``subprocess.Popen`` or an adopted one."""

    pid: int
    returncode: int | None

    def poll(self) -> int | None: ...

    def send_signal(self, sig: int) -> None: ...

    def wait(self, timeout: float | None = None) -> int: ...

    def kill(self) -> None: ...


@dataclass
class StopReport:
    """How a stop went."""

    stop_s: dict[str, float] = field(default_factory=dict)
    """Per child: [s] from its SIGTERM until it was gone."""
    killed: list[str] = field(default_factory=list)
    """Children that outlived their grace and got SIGKILL."""
    slow: list[str] = field(default_factory=list)
    """Children that took longer than their grace but were busy stopping, so were let finish."""
    total_s: float = 0.0
    """Wall time of the whole stop, every group, in [s]."""

    def summary(self) -> str:
        """One line: how many stopped, how long, the slowest, how many were killed."""
        if not self.stop_s:
            return "nothing was running"
        slowest = max(self.stop_s, key=lambda name: self.stop_s[name])
        killed = ", ".join(self.killed) if self.killed else "none"
        return (
            f"stopped {len(self.stop_s)} processes in {self.total_s:.1f} s (slowest: {slowest}, "
            f"{self.stop_s[slowest]:.1f} s; {len(self.slow)} busy past their grace); "
            f"SIGKILLed: {killed}"
        )


@dataclass
class Stopping:
    """A child between its SIGTERM and its end."""

    name: str
    process: ProcessHandle
    grace_s: float
    limit_s: float
    cpu_ticks: int | None = None
    """Its CPU time and its children's at the last look (None: unknown)."""
    looked_s: float = field(default_factory=time.monotonic)

    PROGRESS_WINDOW_S: ClassVar[float] = 0.5
    """How often in [s] its CPU time is looked at."""

    @classmethod
    def of(
        cls,
        name: str,
        process: ProcessHandle,
        own_grace_s: float,
        own_limit_s: float,
        grace_s: float | None,
    ) -> Stopping:
        """A child's own grace and limit, or ``grace_s`` for both when the caller fixes one."""
        grace = own_grace_s if grace_s is None else grace_s
        limit = max(grace, own_limit_s) if grace_s is None else grace_s
        return cls(name, process, grace, limit, family_cpu_ticks(process.pid))

    def overdue(self, elapsed_s: float, now_s: float) -> bool:
        """Whether to kill it now: past its limit, or past its grace, idle since the last look and
        not waiting for a CPU either, nor any of its children (a stuck process, not a busy or a
        starved one)."""
        if elapsed_s >= self.limit_s:
            return True
        if elapsed_s < self.grace_s or now_s - self.looked_s < self.PROGRESS_WINDOW_S:
            return False
        pid = self.process.pid
        before, self.cpu_ticks = self.cpu_ticks, family_cpu_ticks(pid)
        self.looked_s = now_s
        worked = before is not None and self.cpu_ticks is not None and self.cpu_ticks > before
        return not worked and not family_runnable(pid)

    def why_killed(self, elapsed_s: float) -> str:
        if self.limit_s > self.grace_s and elapsed_s >= self.limit_s:
            return f"{self.name} was still stopping after {self.limit_s:.0f} s; killing it"
        return f"{self.name} did not stop in {self.grace_s:.0f} s; killing it"


def stop_group(members: Sequence[Stopping], report: StopReport, say: Callable[[str], None]) -> None:
    """SIGTERM every member, then wait until each is gone, SIGKILLing the overdue ones."""
    signalled_s = time.monotonic()
    for member in members:
        if member.process.poll() is None:
            member.process.send_signal(signal.SIGTERM)
    waiting = {member.name: member for member in members}
    while waiting:
        now = time.monotonic()
        for name, stopping in list(waiting.items()):
            process = stopping.process
            if process.poll() is None and not stopping.overdue(now - signalled_s, now):
                continue
            if process.poll() is None:
                say(stopping.why_killed(now - signalled_s))
                process.kill()
                process.wait()
                report.killed.append(name)
            report.stop_s[name] = time.monotonic() - signalled_s
            if name not in report.killed and report.stop_s[name] > stopping.grace_s:
                report.slow.append(name)
            del waiting[name]
        if waiting:
            time.sleep(0.02)


def describe_end(process: ProcessHandle) -> str:
    """How a child ended, in words: its exit status or the signal that killed it."""
    if isinstance(process, AdoptedProcess):
        return "status unknown: started by an earlier skyquill up"
    returncode = process.returncode
    assert returncode is not None
    if returncode < 0:
        try:
            return f"killed by {signal.Signals(-returncode).name}"
        except ValueError:
            return f"killed by signal {-returncode}"
    return f"exit status {returncode}"

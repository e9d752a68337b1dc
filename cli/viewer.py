"""The operator console in the foreground of ``skyquill up``: a viewer, never the show's lifeline.

:class:`ConsoleViewer` runs ``skyquill tui`` on ``up``'s terminal. When the operator quits it the
show keeps running under the supervisor (``up`` says how to reopen the console or stop the show);
when it crashes it is opened again, at most ``max_crashes`` times a minute, then reported. It
gets SIGTERM if ``up`` itself dies, so it never fights the shell for the terminal.
:class:`UpOutput` is where ``up`` speaks: its log file always, the terminal while no console
covers it and the terminal is still there.
"""

from __future__ import annotations

import contextlib
import ctypes
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import IO, Literal

ConsoleExit = Literal["quit", "crashed", "given_up"]


def _console_dies_with_up() -> None:  # pragma: no cover - runs in the child before exec
    with contextlib.suppress(OSError):
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG


class UpOutput:
    """``skyquill up``'s messages: always to ``log_path``; to stderr unless ``quiet`` (a console
    covers the terminal) or the terminal hung up."""

    def __init__(self, log_path: Path, *, clock: Callable[[], float] = time.time) -> None:
        log_path.parent.mkdir(parents=True, exist_ok=True)
        self._log: IO[str] = log_path.open("a", encoding="utf-8", buffering=1)
        self._clock = clock
        self.log_path = log_path
        self.quiet = False
        self.hung_up = False

    def say(self, line: str) -> None:
        stamp = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(self._clock()))
        self._log.write(f"{stamp} {line}\n")
        if not (self.quiet or self.hung_up):
            with contextlib.suppress(OSError, ValueError):
                print(f"skyquill up: {line}", file=sys.stderr, flush=True)

    def close(self) -> None:
        self._log.close()


class ConsoleViewer:
    """Runs the console; reopens it when it crashes; lets the show run on when it is quit."""

    def __init__(
        self,
        argv: Sequence[str],
        *,
        env: Mapping[str, str] | None = None,
        say: Callable[[str], None],
        on_open: Callable[[int], None] | None = None,
        max_crashes: int = 3,
        window_s: float = 60.0,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self._argv = tuple(argv)
        self._env = dict(env) if env is not None else None
        self._say = say
        self._on_open = on_open
        self._max_crashes = max_crashes
        self._window_s = window_s
        self._clock = clock
        self._crashes: list[float] = []
        self.process: subprocess.Popen[bytes] | None = None

    @property
    def open_now(self) -> bool:
        return self.process is not None

    def open(self) -> None:
        """Start the console in this terminal (it shares ``up``'s terminal and process group)."""
        preexec = _console_dies_with_up if sys.platform.startswith("linux") else None
        self.process = subprocess.Popen(self._argv, env=self._env, preexec_fn=preexec)
        if self._on_open is not None:
            self._on_open(self.process.pid)

    def poll(self) -> ConsoleExit | None:
        """What happened to the console since the last call (None: still open, or closed)."""
        process = self.process
        if process is None or process.poll() is None:
            return None
        self.process = None
        status = process.returncode
        if status == 0:
            return "quit"
        now = self._clock()
        self._crashes = [t for t in self._crashes if now - t < self._window_s] + [now]
        how = f"killed by signal {-status}" if status < 0 else f"exit status {status}"
        if len(self._crashes) > self._max_crashes:
            self._say(
                f"console exited ({how}) {len(self._crashes)} times in a minute; not reopened"
            )
            return "given_up"
        self._say(f"console exited ({how}); reopening it (the show was not affected)")
        self.open()
        return "crashed"

    def close(self, grace_s: float = 3.0) -> None:
        """Stop the console (SIGTERM, SIGKILL after ``grace_s``)."""
        process, self.process = self.process, None
        if process is None or process.poll() is not None:
            return
        process.terminate()
        try:
            process.wait(timeout=grace_s)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


def enter_pressed() -> bool:
    """Whether the operator pressed Enter on ``up``'s terminal (reads that line; never blocks)."""
    import select

    try:
        readable, _, _ = select.select([sys.stdin], [], [], 0.0)
        return bool(readable) and sys.stdin.readline() != ""
    except (OSError, ValueError):
        return False

"""Ctrl-C in the commands that run a show: :func:`hurry_on_ctrl_c` for a simulated one (the demo),
:class:`StopRequests` for ``skyquill up``. Every command ends a Ctrl-C with one line
(``cli/main.py``), never a traceback.

When ``skyquill up`` stops: at once on SIGTERM (``skyquill down``, a script), and on Ctrl-C
only once nothing is in the air, or on a second Ctrl-C after it has said what is.

A Ctrl-C in a terminal is easily pressed by mistake (into the wrong window, to copy text, after
quitting the console). Stopping the show stops every agent, each landing its vehicle first
(``vehicle_agent/stop_signals.py``), which interrupts the characters being written. So, like a
build tool's "press again to force", the first Ctrl-C with vehicles in the air only names them;
a second within :data:`CONFIRM_WINDOW_S` stops the show.
"""

from __future__ import annotations

import contextlib
import signal
import time
from collections.abc import Callable, Iterator
from types import FrameType
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from cli.supervisor import Supervisor

CONFIRM_WINDOW_S = 10.0
"""How long after the question a second Ctrl-C stops the show anyway, wall [s]: time to read two
lines, short enough that a later Ctrl-C is taken as a new first one."""


class StopRequests:
    """Ctrl-C and SIGTERM as they come (record them in the signal handler: nothing slow there);
    :meth:`due` decides in the supervising loop."""

    def __init__(
        self,
        flying: Callable[[], list[str] | None],
        say: Callable[[str], None],
        show: str,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        """``flying()``: the vehicles in the air now, None when that cannot be told (the
        orchestrator does not answer)."""
        self._flying = flying
        self._say = say
        self._show = show
        self._clock = clock
        self._terminated = False
        self._interrupted = False
        self._asked_at_s: float | None = None
        self.by_ctrl_c = False
        """The stop that :meth:`due` called for is a Ctrl-C's (``up`` ends it with one line and
        exit status 130), not a SIGTERM's."""
        self.grounded = False
        """:meth:`due` called for the stop after seeing no vehicle in the air: the supervisor
        may stop every process at once (:meth:`cli.supervisor.Supervisor.stop`)."""

    def terminate(self) -> None:
        """SIGTERM: stop at once."""
        self._terminated = True

    def interrupt(self) -> None:
        """Ctrl-C (SIGINT)."""
        self._interrupted = True

    def due(self) -> bool:
        """Whether the show is to stop now (call it from the loop, often)."""
        if self._terminated:
            return True
        if not self._interrupted:
            return False
        self._interrupted = False
        now_s = self._clock()
        if self._asked_at_s is not None and now_s - self._asked_at_s <= CONFIRM_WINDOW_S:
            self.by_ctrl_c = True
            return True
        flying = self._flying()
        if flying == []:
            self.by_ctrl_c = self.grounded = True
            return True
        what = (
            f"{', '.join(flying)} {'is' if len(flying) == 1 else 'are'} in the air"
            if flying is not None
            else "the orchestrator does not answer: vehicles may be in the air"
        )
        self._say(
            f"{what}. Ctrl-C again within {CONFIRM_WINDOW_S:.0f} s lands them and stops the "
            f"show (`skyquill down {self._show}` does too, and requeues their jobs; "
            "`--now` stops without landing)"
        )
        self._asked_at_s = self._clock()
        return False


@contextlib.contextmanager
def hurry_on_ctrl_c(supervisor: Supervisor) -> Iterator[None]:
    """Within: a Ctrl-C stops the supervised show in a hurry (:meth:`Supervisor.hurry`: a
    simulation, nothing to land; every process at once) and raises ``KeyboardInterrupt``; from
    then on Ctrl-C is ignored, so that the stop runs to its end."""
    interrupted = False

    def on_ctrl_c(_signum: int, _frame: FrameType | None) -> None:
        nonlocal interrupted
        interrupted = True
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        supervisor.hurry()
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGINT, on_ctrl_c)
    try:
        yield
    finally:
        if not interrupted:
            signal.signal(signal.SIGINT, previous)

"""Real autopilots for the conformance suite: ArduCopter SITL and PX4 SIH, one process each.

``start_sitl("ardupilot")`` / ``start_sitl("px4")`` start the binary named by
$SKYQUILL_ARDUCOPTER_SITL (``<ardupilot>/build/sitl/bin/arducopter``) or $SKYQUILL_PX4_SITL
(``<PX4-Autopilot>/build/px4_sitl_default/bin/px4``), built with its listeners bound to
loopback (README, "Real autopilot SITL"), wait until it could arm (3-D GPS fix, local position,
pre-arm checks good; bounded) and return an :class:`AutopilotTarget`. Without the variable
the test is skipped, saying so.

The launching itself is scripts/sitl/start.py (the same code ``start.py SHOW`` runs for a show),
loaded here by path.
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType

import pytest

START_PY = Path(__file__).resolve().parents[2] / "scripts" / "sitl" / "start.py"
SYSTEM_ID = 7
"""MAVLink system id of the autopilot under test (its instance number and ports start.py picks
among those free, beside any show or other test running)."""
READY_TIMEOUT_S = 150.0
"""Longest wait for a fresh instance to be ready to arm, in [s] (ArduCopter's EKF: ~40 s)."""
KINDS = ("ardupilot", "px4")


def _launcher() -> ModuleType:
    name = "skyquill_sitl_start"
    module = sys.modules.get(name)
    if module is None:
        spec = importlib.util.spec_from_file_location(name, START_PY)
        if spec is None or spec.loader is None:
            raise ImportError(f"{START_PY}: cannot load the SITL launcher")
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module  # dataclasses look their module up while being built
        spec.loader.exec_module(module)
    return module


@dataclass
class AutopilotTarget:
    """A running real autopilot, ready to arm."""

    kind: str
    """``ardupilot`` or ``px4``."""
    url: str
    """pymavlink connection string of its link to us (``tcp:...`` or ``udpin:...``)."""
    system_id: int
    """Its MAVLink system id."""
    process: subprocess.Popen[bytes] | None = field(default=None, repr=False)
    """The SITL process (leader of its own process group)."""
    run_dir: Path | None = None
    """Its working directory (eeprom, logs, ``console.log``); removed by :meth:`close`."""

    def clock(self) -> float:
        """The autopilot's time in [s]: SITL runs at the wall clock's pace."""
        return time.monotonic()

    def close(self) -> None:
        """Stop the process and its children; safe to call twice."""
        if self.process is not None:
            _launcher().stop(self.process)
            self.process = None
        if self.run_dir is not None:
            shutil.rmtree(self.run_dir, ignore_errors=True)
            self.run_dir = None

    def console_tail(self, lines: int = 20) -> str:
        """The last lines of the autopilot's console output (for failure messages)."""
        if self.run_dir is None or not (self.run_dir / "console.log").is_file():
            return ""
        text = (self.run_dir / "console.log").read_text(errors="replace")
        return "\n".join(text.splitlines()[-lines:])


def start_sitl(kind: str) -> AutopilotTarget:
    """Start ``kind`` (``ardupilot`` or ``px4``) SITL and wait until it could arm.

    Skips the calling test when the binary's environment variable is not set; fails it (with
    the autopilot's last texts) when the binary does not become ready within
    :data:`READY_TIMEOUT_S`."""
    if kind not in KINDS:
        raise ValueError(f"start_sitl: kind {kind!r} is not one of {KINDS}")
    launch = _launcher()
    variable = launch.ENV_BINARY[kind]
    if not os.environ.get(variable):
        pytest.skip(
            f'{variable} not set: path of the {kind} SITL binary (README, "Real autopilot SITL")'
        )
    try:
        binary = launch.binary_for(kind)
    except launch.SitlError as exc:
        pytest.fail(str(exc), pytrace=False)
    run_dir = Path(tempfile.mkdtemp(prefix=f"skyquill-sitl-{kind}-"))
    inst = launch.claim_instance(kind, SYSTEM_ID, launch.home_lla((0.0, 0.0, 0.0)), binary, run_dir)
    target = AutopilotTarget(kind, inst.url, inst.system_id, launch.start(inst), run_dir)
    try:
        assert target.process is not None
        launch.wait_ready(inst, target.process, READY_TIMEOUT_S)
    except launch.SitlError as exc:
        tail = target.console_tail()
        target.close()
        pytest.fail(f"{kind} SITL: {exc}\nconsole:\n{tail}", pytrace=False)
    except BaseException:
        target.close()
        raise
    return target

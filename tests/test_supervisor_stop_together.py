"""A stop with nothing in the air stops every group of the supervisor's children together; any
other stop keeps the groups' order (agents first: they may have a landing to fly). Issue 34.

The children are real processes, one per stop group, each taking 1 s to stop after its SIGTERM
and writing down when it got it and when it was done (``CLOCK_MONOTONIC``, one clock for every
process of the machine). What is asserted is the order and overlap of those spans, not a speed.
"""

from __future__ import annotations

import itertools
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from job_traces import SHOWS

from bus.messages import VehicleSummary
from cli.interrupt import StopRequests
from cli.showrun import derived_show
from cli.supervisor import ChildSpec, Supervisor, child_env, skyquill_argv
from orchestrator.client import snapshot
from showfile import Show
from trust.settings import ensure_show_keys

pytestmark = pytest.mark.timeout(60)

STOP_TAKES_S = 1.0
"""How long each child takes to stop after its SIGTERM, [s]."""
CHILD = f"""
import signal, sys, time
from pathlib import Path
out = Path(sys.argv[1])
def stop(_signum, _frame):
    got_s = time.monotonic()
    time.sleep({STOP_TAKES_S})
    out.write_text(f"{{got_s}} {{time.monotonic()}}")
    sys.exit(0)
signal.signal(signal.SIGTERM, stop)
out.with_suffix(".ready").touch()
while True:
    time.sleep(0.05)
"""
GROUPS = {"agent uav1": 0, "orchestrator": 1, "sim-mavlink": 2, "router": 3}
"""One child in each of the show's stop groups (``cli.supervisor.show_children``)."""


def _supervised(tmp_path: Path) -> Supervisor:
    specs = [
        ChildSpec(
            name,
            (sys.executable, "-c", CHILD, str(tmp_path / f"{group}.span")),
            stop_group=group,
            lands_on_stop=group == 0,
        )
        for name, group in GROUPS.items()
    ]
    supervisor = Supervisor(specs, say=lambda _line: None)
    supervisor.start()
    deadline = time.monotonic() + 30.0
    while not all((tmp_path / f"{g}.ready").exists() for g in GROUPS.values()):
        assert time.monotonic() < deadline, "the children did not start"
        time.sleep(0.05)
    return supervisor


def _spans(tmp_path: Path) -> list[tuple[float, float]]:
    """Per group, in group order: when it got its SIGTERM and when it was done."""
    spans = []
    for group in sorted(GROUPS.values()):
        got_s, done_s = (tmp_path / f"{group}.span").read_text().split()
        spans.append((float(got_s), float(done_s)))
    return spans


def test_with_nothing_in_the_air_every_group_stops_at_once(tmp_path: Path) -> None:
    report = _supervised(tmp_path).stop(grounded=True)
    spans = _spans(tmp_path)
    assert not report.killed
    latest_signal_s = max(got for got, _ in spans)
    earliest_done_s = min(done for _, done in spans)
    assert latest_signal_s < earliest_done_s  # every child was stopping at once
    assert report.total_s < len(GROUPS) * STOP_TAKES_S  # not the sum of every child's time


def test_otherwise_each_group_stops_after_the_one_before(tmp_path: Path) -> None:
    report = _supervised(tmp_path).stop()
    spans = _spans(tmp_path)
    assert not report.killed
    for (_, done_s), (got_s, _) in itertools.pairwise(spans):
        assert got_s >= done_s  # the agents first, the router last
    assert report.total_s >= len(GROUPS) * STOP_TAKES_S


def test_only_a_ctrl_c_that_found_nothing_in_the_air_stops_together() -> None:
    flying: list[list[str] | None] = [["uav1"], [], None]
    stop = StopRequests(lambda: flying[0], lambda _line: None, "show.yaml", clock=lambda: 0.0)
    stop.interrupt()
    assert not stop.due()  # asked: uav1 is in the air
    stop.interrupt()
    assert stop.due() and stop.by_ctrl_c and not stop.grounded  # confirmed: in order, landing
    flying.pop(0)
    calm = StopRequests(lambda: flying[0], lambda _line: None, "show.yaml")
    calm.interrupt()
    assert calm.due() and calm.by_ctrl_c and calm.grounded
    flying.pop(0)
    unknown = StopRequests(lambda: flying[0], lambda _line: None, "show.yaml", clock=lambda: 0.0)
    unknown.interrupt()
    assert not unknown.due()  # the orchestrator does not answer: asked
    unknown.interrupt()
    assert unknown.due() and not unknown.grounded
    terminated = StopRequests(lambda: [], lambda _line: None, "show.yaml")
    terminated.terminate()
    assert terminated.due() and not terminated.by_ctrl_c and not terminated.grounded


@pytest.mark.multiprocess
@pytest.mark.slow
@pytest.mark.timeout(120)
def test_ctrl_c_in_an_idle_show_is_one_line_and_exit_130(tmp_path: Path) -> None:
    """``skyquill up`` of the solo show, its vehicle on the ground: one Ctrl-C stops it all and
    says so in one line, as the demo does."""
    show_path, show = derived_show(SHOWS / "solo.yaml", tmp_path)
    ensure_show_keys(show)
    up = subprocess.Popen(
        skyquill_argv("up", str(show_path), "--headless", "--no-kiosk"),
        env=child_env(),
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert up.stderr is not None
        for line in up.stderr:  # its announcements end with where the summary is
            if "summary: `skyquill status" in line:
                break
        deadline = time.monotonic() + 60.0
        while not [v for v in _vehicles(show) if v.state == "idle"]:
            assert time.monotonic() < deadline, "uav1 never came up"
            time.sleep(0.2)
        up.send_signal(signal.SIGINT)
        _, after = up.communicate(timeout=60.0)
    finally:
        if up.poll() is None:
            up.kill()
            up.wait()
            subprocess.run(skyquill_argv("down", str(show_path)), env=child_env(), timeout=60)
    lines = [line for line in after.splitlines() if line.strip()]
    assert lines == ["skyquill up: interrupted"], after
    assert up.returncode == 130
    log = (show.database_path.parent / "logs" / "up.log").read_text(encoding="utf-8")
    assert log.splitlines()[-1].endswith("; SIGKILLed: none")  # the account, in up.log


def _vehicles(show: Show) -> list[VehicleSummary]:
    try:
        return list(snapshot(show, timeout_s=2.0).vehicles)
    except Exception:  # the orchestrator is not there yet
        return []

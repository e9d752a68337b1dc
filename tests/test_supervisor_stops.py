"""The supervisor's stops (``cli/supervisor.py``, ``cli/stopping.py``): a child waiting for its own
busy child is stopping, not stuck; a hurried stop tells the agents to stop without landing and
stops every group at once (issue 34). Real child processes and signals."""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from test_agent_supervisor import python, ready_line, wait_ready

from cli.runstate import descendants
from cli.supervisor import ChildSpec, Supervisor

pytestmark = pytest.mark.multiprocess


def test_a_child_waiting_for_its_own_busy_child_is_let_finish_past_its_grace(
    tmp_path: Path,
) -> None:
    """An agent waiting for its planning worker's last picture: idle itself, its child busy."""
    said: list[str] = []
    spin = "import time\nend = time.monotonic() + 2.0\nwhile time.monotonic() < end:\n    pass\n"
    waits = python(
        "import signal, subprocess, sys\n"
        f"def bye(*_):\n    subprocess.run([sys.executable, '-c', {spin!r}])\n    sys.exit(0)\n"
        "signal.signal(signal.SIGTERM, bye)\n" + ready_line(tmp_path, "agent") + "signal.pause()\n"
    )
    supervisor = Supervisor(
        [ChildSpec("agent", waits, stop_grace_s=0.5, stop_limit_s=20.0)], say=said.append
    )
    supervisor.start()
    wait_ready(tmp_path, 1)
    report = supervisor.stop()
    assert said == [] and report.killed == []
    assert 2.0 <= report.stop_s["agent"] < 20.0


def test_descendants_are_found_through_proc(tmp_path: Path) -> None:
    parent = python(
        "import subprocess, sys, time\n"
        "child = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(30)'])\n"
        + ready_line(tmp_path, "parent")
        + "time.sleep(30)\n"
    )
    supervisor = Supervisor([ChildSpec("parent", parent)], say=lambda _line: None)
    supervisor.start()
    try:
        wait_ready(tmp_path, 1)
        pid = supervisor.pid("parent")
        assert pid is not None
        deadline = time.monotonic() + 10.0
        while len(descendants(pid)) != 1:
            assert time.monotonic() < deadline, "the grandchild was not found"
            time.sleep(0.05)
    finally:
        supervisor.stop(grace_s=1.0)


def test_a_hurried_stop_signals_the_agents_first_and_stops_every_group_at_once(
    tmp_path: Path,
) -> None:
    record = tmp_path / "signals.txt"

    def child(name: str) -> tuple[str, ...]:
        return python(
            "import signal, sys, time\n"
            f"def say(what):\n    open({str(record)!r}, 'a').write(what + '\\n')\n"
            f"def now(*_):\n    say('{name} now')\n"
            f"def bye(*_):\n    say(f'{name} term {{time.monotonic()}}')\n"
            "    time.sleep(1.0)\n    sys.exit(0)\n"
            "signal.signal(signal.SIGUSR1, now)\nsignal.signal(signal.SIGTERM, bye)\n"
            + ready_line(tmp_path, name)
            + "time.sleep(60)\n"
        )

    specs = [
        ChildSpec("router", child("router"), stop_group=3),
        ChildSpec("orchestrator", child("orchestrator"), stop_group=1),
        ChildSpec("agent uav1", child("agent"), lands_on_stop=True),
    ]
    supervisor = Supervisor(specs, say=lambda _line: None)
    supervisor.start()
    wait_ready(tmp_path, 3)
    supervisor.hurry()
    deadline = time.monotonic() + 10.0  # the agent has heard the hurry before the stop begins:
    while "agent now" not in (record.read_text() if record.exists() else ""):  # told once only
        assert time.monotonic() < deadline, "the agent never heard the hurry"
        time.sleep(0.01)
    report = supervisor.stop()
    lines = record.read_text().splitlines()
    assert lines[0] == "agent now" and lines.count("agent now") == 1
    terms = {line.split()[0]: float(line.split()[2]) for line in lines[1:]}
    assert sorted(terms) == ["agent", "orchestrator", "router"]
    # each takes 1 s to stop: group by group, each SIGTERM would come a second after the last
    assert max(terms.values()) - min(terms.values()) < 0.9
    assert report.killed == []

"""The show supervisor of ``skyquill up``: restart policy (pure), child processes, a real ``up``."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from processes import running

from bus.keys import ShowKeys
from bus.messages import AIRBORNE_STATES
from bus.session import open_session
from cli.cmd_up import FLYING_QUERY_S
from cli.runstate import AdoptedProcess, ProcessRecord, RunFile, RunFileError, run_file_path
from cli.showrun import derived_show, snapshot, submit_texts, wait_for_jobs
from cli.supervisor import (
    ChildSpec,
    RestartPolicy,
    Supervisor,
    child_env,
    show_children,
    skyquill_argv,
)
from trust.settings import ensure_show_keys, session_settings

SHOWS = Path(__file__).resolve().parent.parent / "shows"


def test_backoff_doubles_up_to_the_cap_and_resets_after_a_stable_run() -> None:
    policy = RestartPolicy(initial_delay_s=0.5, factor=2.0, max_delay_s=3.0, stable_after_s=30.0)
    delays: list[float] = []
    previous = None
    for _ in range(5):
        previous = policy.delay_s(previous, ran_for_s=1.0)
        delays.append(previous)
    assert delays == [0.5, 1.0, 2.0, 3.0, 3.0]
    assert policy.delay_s(3.0, ran_for_s=31.0) == 0.5


def python(code: str) -> tuple[str, ...]:
    return (sys.executable, "-c", code)


def ready_line(folder: Path, name: str) -> str:
    """Code a child runs once its handlers are in place: it says so in ``folder``."""
    return f"open({str(folder / 'ready')!r}, 'a').write('{name}\\n')\n"


def wait_ready(folder: Path, count: int) -> None:
    """Until ``count`` children said they are ready (a loaded machine starts Python slowly)."""
    deadline = time.monotonic() + 60.0
    while not (ready := folder / "ready").exists() or len(ready.read_text().splitlines()) < count:
        assert time.monotonic() < deadline, "the children did not start"
        time.sleep(0.05)


def test_the_router_starts_first_and_stops_last_and_restarts_fast() -> None:
    specs = show_children(Path("r.yaml"), ["uav1"], time_scale=2.0, mavlink_sim=True, kiosk=True)
    names = [spec.name for spec in specs]
    assert names == ["router", "sim-mavlink", "orchestrator", "agent uav1", "kiosk"]
    assert specs[0].argv[-2:] == ("router", "r.yaml")
    assert specs[1].argv[-4:] == ("sim-mavlink", "r.yaml", "--time-scale", "2.0")
    stop_order = sorted(specs, key=lambda spec: spec.stop_group)
    assert [s.name for s in stop_order][-3:] == ["orchestrator", "sim-mavlink", "router"]
    assert specs[0].restart is not None and specs[0].restart.delay_s(None, 0.0) <= 0.2
    assert "sim-mavlink" not in [s.name for s in show_children(Path("r.yaml"), ["uav1"])]


def test_a_child_that_dies_is_restarted_and_the_supervisor_says_so() -> None:
    said: list[str] = []
    policy = RestartPolicy(initial_delay_s=0.05, max_delay_s=0.05)
    supervisor = Supervisor(
        [
            ChildSpec("short", python("pass")),
            ChildSpec("long", python("import time; time.sleep(60)")),
        ],
        policy=policy,
        say=said.append,
    )
    supervisor.start()
    long_pid = supervisor.pid("long")
    try:
        deadline = time.monotonic() + 10.0
        while supervisor.restarts("short") < 2:
            assert time.monotonic() < deadline
            supervisor.poll()
            time.sleep(0.02)
    finally:
        supervisor.stop(grace_s=2.0)
    assert supervisor.pid("long") == long_pid and supervisor.restarts("long") == 0
    assert any(
        "short exited (exit status 0)" in line and "restarting in 0.1 s" in line for line in said
    )
    assert any(line.startswith("short restarted (pid ") for line in said)


@pytest.mark.multiprocess
def test_each_child_gets_its_own_grace_and_only_a_stubborn_one_is_killed(tmp_path: Path) -> None:
    """SIGTERM, then per child its own grace; groups in order: agents, then the router."""
    said: list[str] = []
    record = tmp_path / "stopped.txt"

    def child(name: str, linger_s: float) -> tuple[str, ...]:
        return python(
            "import signal, sys, time\n"
            f"def bye(*_):\n    time.sleep({linger_s})\n"
            f"    open({str(record)!r}, 'a').write('{name}\\n')\n    sys.exit(0)\n"
            "signal.signal(signal.SIGTERM, bye)\n" + ready_line(tmp_path, name) + "time.sleep(60)\n"
        )

    specs = [
        ChildSpec("router", child("router", 0.0), stop_group=3),
        ChildSpec("agent slow", child("agent slow", 1.0), stop_grace_s=3.0),
        ChildSpec("agent stuck", child("agent stuck", 30.0), stop_grace_s=0.5),
    ]
    supervisor = Supervisor(specs, say=said.append)
    supervisor.start()
    wait_ready(tmp_path, 3)
    started = time.monotonic()
    supervisor.stop()
    elapsed = time.monotonic() - started
    assert record.read_text().split("\n")[:2] == ["agent slow", "router"]  # router last
    assert said == ["agent stuck did not stop in 0 s; killing it"]  # the slow one was not killed
    assert 1.0 <= elapsed < 3.0  # the slow agent's 1 s, not its 3 s grace, nor the router's 5 s


@pytest.mark.multiprocess
def test_a_child_busy_stopping_outlives_its_grace_and_only_its_limit_ends_it(
    tmp_path: Path,
) -> None:
    """Past its grace, a child still using CPU is slow (a busy machine), not stuck."""
    said: list[str] = []

    def busy_for(seconds: float) -> tuple[str, ...]:
        return python(
            "import signal, sys, time\n"
            f"def bye(*_):\n    end = time.monotonic() + {seconds}\n"
            "    while time.monotonic() < end:\n        pass\n    sys.exit(0)\n"
            "signal.signal(signal.SIGTERM, bye)\n"
            + ready_line(tmp_path, "busy")
            + "time.sleep(60)\n"
        )

    specs = [
        ChildSpec("agent busy", busy_for(2.0), stop_grace_s=0.5, stop_limit_s=20.0),
        ChildSpec("agent spinning", busy_for(60.0), stop_grace_s=0.5, stop_limit_s=3.0),
    ]
    supervisor = Supervisor(specs, say=said.append)
    supervisor.start()
    wait_ready(tmp_path, 2)
    report = supervisor.stop()
    assert said == ["agent spinning was still stopping after 3 s; killing it"]
    assert report.killed == ["agent spinning"] and 2.0 <= report.stop_s["agent busy"] < 20.0


def test_an_adopted_process_is_supervised_and_replaced_when_it_dies() -> None:
    """A process a previous supervisor started: watched through /proc, restarted as ours."""
    stray = subprocess.Popen(python("import time; time.sleep(60)"))
    record = ProcessRecord.of(stray.pid)
    assert record is not None and record.alive()
    assert not ProcessRecord(stray.pid, record.ticks + 1).alive()  # a reused pid is not it
    said: list[str] = []
    policy = RestartPolicy(initial_delay_s=0.05)
    spec = ChildSpec("worker", python("import time; time.sleep(60)"))
    supervisor = Supervisor([spec], policy=policy, say=said.append)
    supervisor.adopt("worker", AdoptedProcess(record))
    supervisor.start()  # adopted: not started again
    assert supervisor.pid("worker") == stray.pid
    try:
        stray.kill()
        stray.wait()
        deadline = time.monotonic() + 10.0
        while supervisor.restarts("worker") < 1:
            assert time.monotonic() < deadline
            supervisor.poll()
            time.sleep(0.02)
        assert supervisor.pid("worker") not in (None, stray.pid)
    finally:
        supervisor.stop(grace_s=2.0)
    assert said[0].startswith("worker exited (status unknown: started by an earlier skyquill up)")


def test_the_run_file_round_trips_and_refuses_garbage(tmp_path: Path) -> None:
    path = run_file_path(tmp_path / "show.sqlite3")
    assert RunFile.load(path) is None
    me = ProcessRecord.of(os.getpid())
    assert me is not None
    RunFile(path, "solo", me, {"router": me}).save()
    loaded = RunFile.load(path)
    assert loaded is not None and loaded.up == me and loaded.children == {"router": me}
    path.write_text("{not json")
    with pytest.raises(RunFileError, match=str(path)):
        RunFile.load(path)


@pytest.mark.multiprocess
def test_stop_kills_a_child_that_ignores_sigterm(tmp_path: Path) -> None:
    code = (
        "import signal, sys, time\n"
        "signal.signal(signal.SIGTERM, signal.SIG_IGN)\n"
        + ready_line(tmp_path, "stubborn")
        + "time.sleep(60)\n"
    )
    said: list[str] = []
    supervisor = Supervisor([ChildSpec("stubborn", python(code))], say=said.append)
    supervisor.start()
    wait_ready(tmp_path, 1)
    started = time.monotonic()
    supervisor.stop(grace_s=0.5)
    assert time.monotonic() - started < 5.0
    assert len(said) == 1 and said[0].startswith("stubborn did not stop") and "killing" in said[0]
    supervisor.poll()
    assert supervisor.pid("stubborn") is None


def _children_of(pid: int) -> set[int]:
    found = set()
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                found.add(int(entry.name))
    return found


@pytest.mark.multiprocess
@pytest.mark.slow
@pytest.mark.timeout(120)
@pytest.mark.skipif(not Path("/proc").is_dir(), reason="reads /proc")
def test_skyquill_up_runs_a_show_and_stops_every_process_on_ctrl_c(tmp_path: Path) -> None:
    """A first job written; then, with the vehicle writing the second, a first Ctrl-C only names
    it (``cli/interrupt.py``) and a second stops the show."""
    show_path, show = derived_show(SHOWS / "solo.yaml", tmp_path, time_scale=6.0)
    ensure_show_keys(show)  # `up` would make them too, but this test's session needs them first
    up = subprocess.Popen(
        skyquill_argv("up", str(show_path), "--headless", "--no-kiosk"),
        env=child_env(),
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        operator = session_settings(show, "operator")
        with open_session(operator, role="client", open_timeout_s=20.0) as session:
            keys = ShowKeys(show.show_id)
            (reply,) = submit_texts(session, keys, ["一"], timeout_s=60.0)
            (job,) = wait_for_jobs(session, keys, [str(reply.job_id)], timeout_s=60.0)
            assert job.state == "done" and job.metrics is not None
            assert job.metrics.written is not None and job.metrics.written.width_px == 160
            children = _children_of(up.pid)
            assert len(children) == 3  # router, orchestrator and one agent
            submit_texts(session, keys, ["十"], timeout_s=60.0)
            deadline = time.monotonic() + 60.0
            while snapshot(session, keys).vehicles[0].state not in AIRBORNE_STATES:
                assert time.monotonic() < deadline, "the second job never flew"
                time.sleep(0.1)
        up.send_signal(signal.SIGINT)
        time.sleep(FLYING_QUERY_S + 1.0)
        assert up.poll() is None  # asked, still running
        up.send_signal(signal.SIGINT)
        _, stderr = up.communicate(timeout=30.0)
    finally:
        if up.poll() is None:
            up.kill()
            up.wait()
            # its children outlive a killed `up` by design: never leave them to the next test
            subprocess.run(skyquill_argv("down", str(show_path)), env=child_env(), timeout=60)
    assert up.returncode == 130, stderr
    assert stderr.splitlines()[-1] == "skyquill up: interrupted"
    assert "skyquill up: stopping" in stderr and "killing" not in stderr  # landing first
    assert "skyquill up: stopped 3 processes" in stderr
    assert "uav1 is in the air. Ctrl-C again" in stderr
    assert not [pid for pid in children if running(pid)]
    assert not run_file_path(show.database_path).exists()

"""``skyquill down`` lands the vehicles in the air before it stops their agents, and takes their
jobs back; ``--now`` stops without landing; Ctrl-C in ``skyquill demo`` is one line and a quick
exit (issue 34). Real processes over real Zenoh: ``skyquill up`` and its children."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from test_mavlink_mixed_show import free_udp_port

from bus.keys import ShowKeys
from bus.messages import AIRBORNE_STATES, JobState, Telemetry, VehicleStatus
from bus.pubsub import subscribe
from bus.session import Session, open_session
from cli.runstate import ProcessRecord, RunFile, run_file_path
from cli.showrun import derived_show, snapshot, submit_texts
from cli.supervisor import child_env, skyquill_argv
from orchestrator.store import JobStore
from showfile import Show, load_show
from trust.settings import ensure_show_keys, session_settings

pytestmark = [pytest.mark.multiprocess, pytest.mark.slow]

SOLO = Path(__file__).resolve().parent.parent / "shows" / "solo.yaml"
TIME_SCALE = 2.0
"""Fast enough, slow enough that ``down`` finds the vehicle writing (a character takes 20 s)."""
GROUND_M = 0.05
"""Highest a vehicle resting on the ground is, [m] (its reference point rests at z = 0)."""


@dataclass
class Watch:
    """What uav1 said and when (monotonic [s]), and when its agent process was gone."""

    statuses: list[tuple[float, VehicleStatus]] = field(default_factory=list)
    heights_m: list[tuple[float, float]] = field(default_factory=list)
    agent_gone_s: float | None = None
    lock: threading.Lock = field(default_factory=threading.Lock)

    def status(self, _key: str, status: VehicleStatus) -> None:
        with self.lock:
            self.statuses.append((time.monotonic(), status))

    def telemetry(self, _key: str, sample: Telemetry) -> None:
        with self.lock:
            self.heights_m.append((time.monotonic(), sample.position_m_enu[2]))

    def follow(self, agent: ProcessRecord) -> None:
        def wait() -> None:
            while agent.alive():
                time.sleep(0.01)
            self.agent_gone_s = time.monotonic()

        threading.Thread(target=wait, daemon=True).start()

    def landed_at_s(self) -> float | None:
        with self.lock:
            landed = [t for t, st in self.statuses if st.state not in AIRBORNE_STATES]
            flew = [t for t, st in self.statuses if st.state in AIRBORNE_STATES]
        after = [t for t in landed if flew and t > flew[-1]]
        return after[0] if after else None

    def last_height_m(self, before_s: float) -> float:
        with self.lock:
            return [z for t, z in self.heights_m if t <= before_s][-1]


def _solo(out: Path, backend: str) -> tuple[Path, Show]:
    """The solo show; ``backend: mavlink``: its vehicle a simulated autopilot that ``up`` runs
    (``skyquill sim-mavlink``), as shows/rehearsal-mavlink.yaml has them."""
    if backend == "sim":
        return derived_show(SOLO, out, time_scale=TIME_SCALE)
    base = load_show(SOLO)
    url = f"udp:127.0.0.1:{free_udp_port()}"
    update = {"backend": "mavlink", "mavlink_url": url, "mavlink_system_id": 1}
    return derived_show(
        SOLO,
        out,
        time_scale=TIME_SCALE,
        vehicles=tuple(v.model_copy(update=update) for v in base.vehicles),
        mavlink_sim=base.mavlink_sim.model_copy(update={"enabled": True}),
        controller=base.controller.model_copy(update={"preset": "default"}),
        planning=base.planning.model_copy(update={"pace": "nominal"}),
    )


@pytest.fixture(params=["sim", "mavlink"])
def solo_up(
    tmp_path: Path, request: pytest.FixtureRequest
) -> Iterator[tuple[Path, Show, subprocess.Popen[bytes]]]:
    path, show = _solo(tmp_path, request.param)
    ensure_show_keys(show)
    log = (tmp_path / "up.err").open("wb")
    up = subprocess.Popen(
        skyquill_argv("up", str(path), "--headless", "--no-kiosk"), env=child_env(), stderr=log
    )
    try:
        yield path, show, up
    finally:
        if up.poll() is None:
            up.kill()
        if RunFile.load(run_file_path(show.database_path)) is not None:  # failed midway
            subprocess.run(skyquill_argv("down", str(path), "--now"), env=child_env(), timeout=90)
        log.close()


def _operator(show: Show) -> Session:
    return open_session(session_settings(show, "operator"), role="client", open_timeout_s=30.0)


def _agent(show: Show) -> ProcessRecord:
    deadline = time.monotonic() + 30.0
    while time.monotonic() < deadline:
        runfile = RunFile.load(run_file_path(show.database_path))
        if runfile is not None and "agent uav1" in runfile.children:
            return runfile.children["agent uav1"]
        time.sleep(0.1)
    raise AssertionError("no agent uav1 in the run file")


def _writing(session: Session, show: Show, text: str) -> JobState:
    """Submit ``text``; the job once uav1 has written a tenth of it."""
    keys = ShowKeys(show.show_id)
    (reply,) = submit_texts(session, keys, [text], timeout_s=60.0)
    deadline = time.monotonic() + 90.0
    while time.monotonic() < deadline:
        for job in snapshot(session, keys).jobs:
            if job.job_id == reply.job_id and job.state == "writing" and job.progress > 0.1:
                return job
        time.sleep(0.1)
    raise AssertionError(f"{text} was not being written")


def _watching(session: Session, show: Show) -> Watch:
    keys, watch = ShowKeys(show.show_id), Watch()
    subscribe(session, keys.vehicle_status("uav1"), VehicleStatus, watch.status)
    subscribe(session, keys.telemetry("uav1"), Telemetry, watch.telemetry)
    return watch


def _down(path: Path, *flags: str) -> tuple[subprocess.CompletedProcess[str], float]:
    started = time.monotonic()
    done = subprocess.run(
        skyquill_argv("down", str(path), *flags),
        env=child_env(),
        capture_output=True,
        text=True,
        timeout=120,
    )
    return done, started


def test_down_lands_a_writing_vehicle_before_its_agent_stops_and_requeues_its_job(
    solo_up: tuple[Path, Show, subprocess.Popen[bytes]],
) -> None:
    path, show, up = solo_up
    with _operator(show) as session:
        watch = _watching(session, show)
        job = _writing(session, show, "永")
        watch.follow(_agent(show))
        done, started = _down(path)
        assert done.returncode == 0, done.stderr
        assert up.wait(timeout=30) == 0
    landed_s = watch.landed_at_s()
    assert landed_s is not None, f"uav1 never said it landed: {done.stdout}"
    assert watch.agent_gone_s is not None and landed_s < watch.agent_gone_s
    assert watch.last_height_m(watch.agent_gone_s) < GROUND_M  # on the ground, not hovering
    assert "uav1 landed after" in done.stdout and "stopped" in done.stdout, done.stdout
    print(done.stdout)
    with JobStore(show.database_path) as store:
        stored = store.load()
    (again,) = [j for j in stored.jobs if j.job_id == job.job_id]
    assert again.state == "queued"  # not lost, not failed: another vehicle may write it
    assert stored.dirty_boards == ["b1"]  # half-written: it waits for a fresh sheet
    assert stored.held_vehicles == ["uav1"] and stored.queue_paused
    print(
        f"\ndown: uav1 landed {landed_s - started:.1f} s after down began, its agent gone "
        f"{watch.agent_gone_s - started:.1f} s, down exited {time.monotonic() - started:.1f} s"
        f" (load {_load()})",
        file=sys.stderr,
    )


@pytest.mark.parametrize("solo_up", ["sim"], indirect=True)
def test_with_the_orchestrator_gone_down_tells_each_vehicle_to_land(
    solo_up: tuple[Path, Show, subprocess.Popen[bytes]],
) -> None:
    """The orchestrator frozen (SIGSTOP): ``down`` lands the vehicle itself; the job stays the
    vehicle's in the store, for the next orchestrator to take back (its agent will have started
    anew without it: ``orchestrator/presence.py``)."""
    path, show, up = solo_up
    with _operator(show) as session:
        watch = _watching(session, show)
        job = _writing(session, show, "永")
        runfile = RunFile.load(run_file_path(show.database_path))
        assert runfile is not None
        orchestrator = runfile.children["orchestrator"]
        watch.follow(_agent(show))
        os.kill(orchestrator.pid, signal.SIGSTOP)
        done, started = _down(path)
        assert done.returncode == 0, done.stderr
        assert up.wait(timeout=30) == 0
    assert "the orchestrator does not answer" in done.stdout, done.stdout
    print(done.stdout, f"{time.monotonic() - started:.1f} s")
    landed_s = watch.landed_at_s()
    assert landed_s is not None and watch.agent_gone_s is not None
    assert landed_s < watch.agent_gone_s
    assert watch.last_height_m(watch.agent_gone_s) < GROUND_M
    assert not orchestrator.alive()
    with JobStore(show.database_path) as store:
        (again,) = [j for j in store.load().jobs if j.job_id == job.job_id]
    assert again.state == "writing" and again.vehicle_id == "uav1"


@pytest.mark.parametrize("solo_up", ["sim"], indirect=True)
def test_a_vehicle_not_down_in_time_keeps_its_agent_and_down_says_how_to_go_on(
    solo_up: tuple[Path, Show, subprocess.Popen[bytes]],
) -> None:
    path, show, up = solo_up
    with _operator(show) as session:
        _writing(session, show, "永")
        agent = _agent(show)
        done, _ = _down(path, "--land-timeout", "0.2")  # a landing takes seconds
        assert done.returncode == 1
        assert "uav1 has not said it landed in 0 s" in done.stdout, done.stdout
        assert "uav1 may still be in the air: the show keeps running" in done.stderr
        assert "--now` stops without landing" in done.stderr
        assert up.poll() is None and agent.alive()  # nothing stopped: its link stays up
        again, _ = _down(path)  # landed meanwhile, or landing: it is waited for
        assert again.returncode == 0, again.stderr
        assert up.wait(timeout=30) == 0


def test_down_now_stops_without_landing(
    solo_up: tuple[Path, Show, subprocess.Popen[bytes]],
) -> None:
    path, show, up = solo_up
    with _operator(show) as session:
        watch = _watching(session, show)
        _writing(session, show, "永")
        watch.follow(_agent(show))
        done, started = _down(path, "--now")
        assert done.returncode == 0, done.stderr
        assert up.wait(timeout=30) == 0
    assert watch.agent_gone_s is not None
    assert watch.landed_at_s() is None  # it never said it landed...
    assert watch.last_height_m(watch.agent_gone_s) > 0.3  # ...it was still up there
    assert "landing" not in done.stdout, done.stdout
    print(f"\ndown --now: agent gone {watch.agent_gone_s - started:.1f} s (load {_load()})")


def test_ctrl_c_in_the_demo_is_one_line_and_a_quick_exit(tmp_path: Path) -> None:
    demo = subprocess.Popen(
        skyquill_argv("demo", "永", "--out", str(tmp_path)),
        env=child_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert demo.stdout is not None
        for line in demo.stdout:  # until a vehicle writes: processes up, vehicles in the air
            if "writing on" in line:
                break
        else:
            raise AssertionError("the demo ended before writing")
        demo.send_signal(signal.SIGINT)
        sent_s = time.monotonic()
        _, stderr = demo.communicate(timeout=30)
        took_s = time.monotonic() - sent_s
    finally:
        if demo.poll() is None:
            demo.kill()
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert lines == ["skyquill demo: interrupted"], stderr
    assert demo.returncode == 130
    assert took_s < 2.0, f"{took_s:.1f} s (load {_load()})"
    print(f"\nCtrl-C in the demo: exit in {took_s:.2f} s (load {_load()})")


def _load() -> str:
    return Path("/proc/loadavg").read_text().split()[0]

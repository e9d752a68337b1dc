"""A show survives its processes dying or freezing, and never writes a character twice.

SIGKILL of the router, of the orchestrator and of an agent, SIGSTOP of an agent for 20 s, and of the
orchestrator for 2.5 s three times over one character, mid-show: one show of three simulated
vehicles runs for these (every process of it a supervised child, router included, as under
``skyquill up``; loopback, mutual TLS, sped up). SIGKILL of the console and of ``skyquill up``
itself: a real ``skyquill up`` each (one vehicle).

After each, the show's promises are checked: every acknowledged submission is ``done`` in the
orchestrator's SQLite store and was written completely exactly once (one job folder of the agent
that flew it to its end), and no vehicle put ink for a job while or after another vehicle had it
(pen-down telemetry of two vehicles for one job never interleaves).
"""

from __future__ import annotations

import itertools
import os
import pty
import signal
import sqlite3
import subprocess
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from show_probe import answering_snapshot

from bus.keys import ShowKeys
from bus.messages import (
    AIRBORNE_STATES,
    CommandReply,
    Event,
    JobState,
    OperatorCommand,
    ShowSnapshot,
    Telemetry,
)
from bus.pubsub import subscribe
from bus.rpc import query_one
from bus.session import Session, open_session
from cli.runstate import RunFile, run_file_path
from cli.showrun import ShowRun, Stagehand, derived_show, snapshot, submit_texts, wait_for_jobs
from cli.supervisor import child_env, skyquill_argv
from showfile import Show, load_show
from trust.settings import ensure_show_keys, session_settings
from vehicle_agent.job_files import written_whole

pytestmark = [pytest.mark.multiprocess, pytest.mark.slow, pytest.mark.timeout(120)]

SHOWS = Path(__file__).resolve().parent.parent / "shows"
TIME_SCALE = 6.0
JOB_TIMEOUT_S = 60.0
FREEZE_S = 20.0
ATTEMPT_GAP_S = 2.0
"""Pen-down telemetry of one vehicle for one job this far apart in [s] is two of its attempts
(a pause between two strokes is a fraction of a second at ``TIME_SCALE``; another attempt needs
the job taken back, assigned, flown to the board)."""


@dataclass(frozen=True)
class Ink:
    arrived_s: float
    """Monotonic time the telemetry sample arrived here, [s]."""
    vehicle_id: str
    job_id: str


@dataclass
class LiveShow:
    run: ShowRun
    session: Session
    events: list[Event] = field(default_factory=list)
    ink: list[Ink] = field(default_factory=list)
    acknowledged: list[str] = field(default_factory=list)
    heard_at_s: dict[str, float] = field(default_factory=dict)
    """Monotonic time of each vehicle's latest telemetry here."""
    lock: threading.Lock = field(default_factory=threading.Lock)

    @property
    def keys(self) -> ShowKeys:
        return self.run.keys

    def submit(self, texts: list[str]) -> list[str]:
        ids = [str(r.job_id) for r in submit_texts(self.session, self.keys, texts)]
        self.acknowledged.extend(ids)
        return ids

    def wait(self, job_ids: list[str]) -> list[JobState]:
        return wait_for_jobs(self.session, self.keys, job_ids, timeout_s=JOB_TIMEOUT_S)

    def wait_until_writing(self, job_ids: list[str]) -> JobState:
        """The first of ``job_ids`` seen writing and under half done (a character short enough
        to pass that window between two looks, L at ``TIME_SCALE`` on a loaded CI host, is not
        one to strike in: the failure says what was last seen)."""
        deadline = time.monotonic() + JOB_TIMEOUT_S
        seen: dict[str, tuple[str, float]] = {}
        while time.monotonic() < deadline:
            jobs = {j.job_id: j for j in self.snapshot().jobs}
            for job_id in job_ids:
                job = jobs.get(job_id)
                if job is not None:
                    seen[job_id] = (job.state, job.progress)
                if job is not None and job.state == "writing" and 0.05 < job.progress < 0.5:
                    return job  # under half done: not finished before the fault strikes
            time.sleep(0.1)
        raise AssertionError(f"none of {job_ids} seen under half written; last seen: {seen}")

    def wait_until_all_writing(self, job_ids: list[str]) -> dict[str, str | None]:
        """Every job in ``job_ids`` flown by its vehicle (planned, in transit or being written),
        at least one being written, none half done: job -> vehicle."""
        deadline = time.monotonic() + JOB_TIMEOUT_S
        while time.monotonic() < deadline:
            jobs = {j.job_id: j for j in self.snapshot().jobs}
            mine = [j for j in (jobs.get(job_id) for job_id in job_ids) if j is not None]
            active = [j for j in mine if j.state in ("assigned", "writing") and j.progress < 0.5]
            writing = [j for j in active if j.state == "writing" and j.progress > 0.0]
            if len(active) == len(job_ids) and writing:
                return {j.job_id: j.vehicle_id for j in active}
            time.sleep(0.05)
        raise AssertionError(f"{job_ids} were not all being written at once")

    def heard_from_every_vehicle(self, since_s: float, within_s: float) -> float:
        """Seconds from ``since_s`` (monotonic) until telemetry of every vehicle arrived here."""
        vehicles = {v.id for v in self.run.show.vehicles}
        deadline = since_s + within_s
        while time.monotonic() < deadline:
            with self.lock:
                heard = {vid for vid, at_s in self.heard_at_s.items() if at_s >= since_s}
            if heard == vehicles:
                with self.lock:
                    return max(self.heard_at_s[v] for v in vehicles) - since_s
            time.sleep(0.01)
        raise AssertionError(f"not every vehicle heard within {within_s} s")

    def events_since(self, kind: str, since_s: float) -> list[Event]:
        with self.lock:
            return [e for e in self.events if e.kind == kind and e.time_s >= since_s]

    def snapshot(self) -> ShowSnapshot:
        """The orchestrator's view; empty while it does not answer (starting, restarting)."""
        shown = answering_snapshot(self.session, self.keys)
        return shown or ShowSnapshot(
            show_id="", time_s=0.0, queue_paused=False, jobs=[], vehicles=[]
        )

    def events_of(self, kind: str, vehicle_id: str) -> list[Event]:
        with self.lock:
            return [e for e in self.events if e.kind == kind and e.vehicle_id == vehicle_id]

    def ink_after(self, vehicle_id: str, job_id: str, since_s: float) -> list[Ink]:
        with self.lock:
            return [
                i
                for i in self.ink
                if (i.vehicle_id, i.job_id) == (vehicle_id, job_id) and i.arrived_s >= since_s
            ]

    def wait_ready(self, vehicle_id: str, timeout_s: float = 30.0) -> None:
        """The vehicle present and on the ground; held (lost in the air, or in fault), it is
        released as the operator would after checking it."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            vehicles = {v.vehicle_id: v for v in self.snapshot().vehicles}
            view = vehicles.get(vehicle_id)
            if view is not None and view.alive and view.state in ("idle", "landed"):
                if not view.held:
                    return
                self.command(OperatorCommand(command="release", vehicle_id=vehicle_id))
            time.sleep(0.2)
        raise AssertionError(f"{vehicle_id} did not come back")

    def command(self, command: OperatorCommand) -> CommandReply:
        reply = query_one(self.session, self.keys.command, command, CommandReply, timeout_s=5.0)
        assert reply.ok, reply
        return reply

    def check_written_once(self) -> None:
        """Every acknowledged job done once, completely written once, never by two at once."""
        jobs = self.wait(list(self.acknowledged))
        assert [j.state for j in jobs] == ["done"] * len(jobs), [(j.job_id, j.state) for j in jobs]
        show = self.run.show
        stored = sqlite3.connect(f"file:{show.database_path}?mode=ro", uri=True)
        try:
            states = dict(stored.execute("SELECT job_id, state FROM jobs").fetchall())
        finally:
            stored.close()
        assert all(states[j] == "done" for j in self.acknowledged), states
        folders = [p for p in (show.database_path.parent / "jobs").iterdir()]
        for job_id in self.acknowledged:  # a broken-off attempt keeps its folder too
            mine = [p for p in folders if p.name.startswith(f"{job_id}-")]
            written = [p.name for p in mine if written_whole(p)]
            assert len(written) == 1, f"{job_id} written completely {len(written)} times"
        with self.lock:
            ink = list(self.ink)
        for job_id in self.acknowledged:
            spans = sorted(_ink_spans(ink, job_id))
            for earlier, later in itertools.pairwise(spans):
                assert earlier[1] < later[0], f"{job_id}: {earlier[2]} and {later[2]} both inked"


def _ink_spans(ink: list[Ink], job_id: str) -> list[tuple[float, float, str]]:
    """(first, last arrival [s], vehicle) of each attempt's pen-down samples for ``job_id``: a
    vehicle's samples more than ``ATTEMPT_GAP_S`` apart belong to two attempts of its."""
    times: dict[str, list[float]] = {}
    for sample in ink:
        if sample.job_id == job_id:
            times.setdefault(sample.vehicle_id, []).append(sample.arrived_s)
    spans = []
    for vid, arrived in times.items():
        arrived.sort()
        start = arrived[0]
        for before, after in itertools.pairwise(arrived):
            if after - before > ATTEMPT_GAP_S:
                spans.append((start, before, vid))
                start = after
        spans.append((start, arrived[-1], vid))
    return spans


@pytest.fixture(scope="module")
def live(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LiveShow]:
    out = tmp_path_factory.mktemp("resilience")
    base = load_show(SHOWS / "airshow-2014.yaml")
    path, show = derived_show(
        SHOWS / "airshow-2014.yaml",
        out,
        time_scale=TIME_SCALE,
        vehicles=base.vehicles[:3],
        controller=base.controller.model_copy(update={"preset": "default"}),
    )
    assert show.security.mode == "mtls" and show.policy.lost_after_s == 1.5
    with (
        ShowRun(path, show, log_dir=out / "logs", say=lambda _: None) as run,
        run.client() as session,
    ):
        live = LiveShow(run, session)

        def on_event(_key: str, event: Event) -> None:
            with live.lock:
                live.events.append(event)

        def on_telemetry(_key: str, t: Telemetry) -> None:
            with live.lock:
                live.heard_at_s[t.vehicle_id] = time.monotonic()
                if t.pen_down and t.job_id is not None:
                    live.ink.append(Ink(time.monotonic(), t.vehicle_id, t.job_id))

        subs = [
            subscribe(session, run.keys.events, Event, on_event),
            subscribe(session, run.keys.telemetry_all, Telemetry, on_telemetry),
        ]
        for vehicle in show.vehicles:
            live.wait_ready(vehicle.id, timeout_s=60.0)
        with Stagehand(session, run.keys):  # fresh sheets on boards left half-written
            yield live
        for sub in subs:
            sub.undeclare()  # type: ignore[no-untyped-call]


def _new_pid(run: ShowRun, name: str, old: int, within_s: float) -> float:
    """Seconds until the supervisor runs a new ``name``; fails after ``within_s``."""
    started = time.monotonic()
    while run.supervisor.pid(name) in (None, old):
        assert time.monotonic() - started < within_s, f"{name} not restarted in {within_s} s"
        time.sleep(0.02)
    return time.monotonic() - started


def _strike_while_all_write(live: LiveShow, texts: list[str], victims: list[str]) -> None:
    """Kill ``victims`` (supervised processes) one after the other with every vehicle writing:
    each character is finished by the vehicle that was writing it, on its own board, with no
    board left half-written and nothing asked of the operator."""
    job_ids = live.submit(texts)
    writers = live.wait_until_all_writing(job_ids)
    struck_at = time.time()
    for name in victims:
        pid = live.run.supervisor.pid(name)
        assert pid is not None
        os.kill(pid, signal.SIGKILL)
        back_s = _new_pid(live.run, name, pid, within_s=10.0)
        print(f"\n{name} restarted after {back_s:.2f} s")
        if name == "router":
            heard_s = live.heard_from_every_vehicle(since_s=time.monotonic(), within_s=5.0)
            print(f"every vehicle heard again {heard_s:.2f} s after the new router started")
    jobs = live.wait(job_ids)
    with live.lock:
        said = [f"{e.kind}: {e.message}" for e in live.events if e.job_id in writers]
    assert {j.job_id: j.vehicle_id for j in jobs} == writers, said
    dirty = [e.message for e in live.events_since("board_dirty", struck_at)]
    assert dirty == [], dirty
    if victims == ["router"]:  # repaired by the supervisor before anyone was taken as lost
        assert live.events_since("vehicle_lost", struck_at) == []
    live.check_written_once()  # every client reconnected by itself and re-declared everything


def test_the_router_killed_while_all_write_costs_no_character(live: LiveShow) -> None:
    _strike_while_all_write(live, ["永", "光", "马"], ["router"])


def test_the_orchestrator_killed_while_all_write_costs_no_character(live: LiveShow) -> None:
    _strike_while_all_write(live, ["东", "风", "雨"], ["orchestrator"])


def test_router_and_orchestrator_killed_while_all_write_cost_no_character(live: LiveShow) -> None:
    _strike_while_all_write(live, ["书", "画", "龙"], ["router", "orchestrator"])


def test_an_agent_killed_mid_character_is_lost_within_2_s_and_another_writes_it(
    live: LiveShow,
) -> None:
    (job_id,) = live.submit(["水"])  # long enough to be seen under half written
    victim = str(live.wait_until_writing([job_id]).vehicle_id)
    pid = live.run.supervisor.pid(f"agent {victim}")
    assert pid is not None
    killed_at = time.time()
    os.kill(pid, signal.SIGKILL)
    (job,) = live.wait([job_id])
    assert job.vehicle_id != victim and job.attempts >= 2  # more: an assignment unanswered
    # lost; or restarted by the supervisor so fast that its new self says it has no job first
    taken_back = [
        e.time_s - killed_at
        for kind in ("vehicle_lost", "job_requeued")
        for e in live.events_of(kind, victim)
        if e.time_s >= killed_at
    ]
    assert taken_back and min(taken_back) <= 2.0, taken_back
    print(f"\nkilled agent's job taken back after {min(taken_back):.2f} s")
    live.wait_ready(victim)  # restarted by the supervisor
    live.check_written_once()


def test_an_agent_frozen_20_s_is_lost_within_2_s_and_never_inks_its_old_job(
    live: LiveShow,
) -> None:
    (job_id,) = live.submit(["火"])  # long enough to be seen under half written
    victim = str(live.wait_until_writing([job_id]).vehicle_id)
    pid = live.run.supervisor.pid(f"agent {victim}")
    assert pid is not None
    stopped_at = time.time()
    os.kill(pid, signal.SIGSTOP)
    try:
        deadline = time.monotonic() + 10.0
        while not [e for e in live.events_of("vehicle_lost", victim) if e.time_s > stopped_at]:
            assert time.monotonic() < deadline, "a frozen agent was never taken as lost"
            time.sleep(0.05)
        lost = [e for e in live.events_of("vehicle_lost", victim) if e.time_s > stopped_at]
        assert lost[0].time_s - stopped_at <= 2.0, lost  # as fast as a dead one
        print(f"\nfrozen agent taken as lost after {lost[0].time_s - stopped_at:.2f} s")
        time.sleep(max(0.0, stopped_at + FREEZE_S - time.time()))
    finally:
        os.kill(pid, signal.SIGCONT)
    resumed_at = time.monotonic()
    (job,) = live.wait([job_id])
    assert job.state == "done" and job.vehicle_id != victim
    live.wait_ready(victim)
    # fenced before its next tick (the tick the freeze interrupted may finish: 0.1 s of slack)
    assert live.ink_after(victim, job_id, resumed_at + 0.1) == []
    agent_log = (live.run.show.database_path.parent / "logs" / f"{victim}.log").read_text()
    assert f"gave job {job_id} up: " in agent_log  # it stalled, or went unacknowledged
    assert live.run.supervisor.restarts(f"agent {victim}") <= 1  # not restarted for freezing
    held = [e.message for e in live.events_of("vehicle_held", victim) if e.time_s > stopped_at]
    assert held and "lost while writing" in held[0], held  # released above, as an operator would
    live.check_written_once()


def test_the_orchestrator_frozen_three_times_over_a_character_costs_it_nothing(
    live: LiveShow,
) -> None:
    """The orchestrator frozen past ``lost_after_s`` three times while a character is written
    (SIGSTOP 2.5 s; a laptop under load, a debugger): its writer goes on, on its write fence
    (``bus/fence.py``; before, it gave the job up each time and another vehicle began it again),
    and the character is written once, by it, at the first attempt."""
    (job_id,) = live.submit(["永"])
    pid = live.run.supervisor.pid("orchestrator")
    assert pid is not None
    writer = live.wait_until_writing([job_id]).vehicle_id
    stopped_at = time.time()
    for _ in range(3):
        os.kill(pid, signal.SIGSTOP)
        try:
            time.sleep(live.run.show.policy.lost_after_s + 1.0)
        finally:
            os.kill(pid, signal.SIGCONT)
        time.sleep(0.3)
    (job,) = live.wait([job_id])
    assert (job.state, job.vehicle_id, job.attempts) == ("done", writer, 1), job
    with live.lock:
        said = [e.kind for e in live.events if e.job_id == job_id and e.time_s >= stopped_at]
    assert "job_requeued" not in said and "board_dirty" not in said, said
    live.check_written_once()


# --- a real `skyquill up`: its console and itself ------------------------------------------------


def _solo(tmp_path: Path) -> tuple[Path, Show]:
    path, show = derived_show(SHOWS / "solo.yaml", tmp_path, time_scale=TIME_SCALE)
    ensure_show_keys(show)  # `up` would make them too, but this test's session needs them first
    return path, show


def _operator(show: Show) -> Session:
    """An operator's session, once the router `up` started listens."""
    operator = session_settings(show, "operator")
    return open_session(operator, role="client", open_timeout_s=30.0)


def _run_file(show: Show, wanted: Callable[[RunFile], bool], timeout_s: float = 30.0) -> RunFile:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        runfile = RunFile.load(run_file_path(show.database_path))
        if runfile is not None and wanted(runfile):
            return runfile
        time.sleep(0.1)
    raise AssertionError(f"no run file as wanted in {run_file_path(show.database_path)}")


def _write_one(session: Session, show: Show, text: str) -> JobState:
    keys = ShowKeys(show.show_id)
    (reply,) = submit_texts(session, keys, [text], timeout_s=60.0)
    (job,) = wait_for_jobs(session, keys, [str(reply.job_id)], timeout_s=JOB_TIMEOUT_S)
    return job


def _wait_landed(session: Session, show: Show, timeout_s: float = 60.0) -> None:
    deadline = time.monotonic() + timeout_s
    keys = ShowKeys(show.show_id)
    while any(v.state in AIRBORNE_STATES for v in snapshot(session, keys).vehicles):
        assert time.monotonic() < deadline, "the vehicle did not land"
        time.sleep(0.2)


def _down(path: Path) -> str:
    done = subprocess.run(
        skyquill_argv("down", str(path)),
        env=child_env(),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_the_console_is_a_viewer_killed_it_reopens_quit_the_show_runs_on(tmp_path: Path) -> None:
    path, show = _solo(tmp_path)
    main, tty = pty.openpty()
    up = subprocess.Popen(
        skyquill_argv("up", str(path), "--no-kiosk"),
        env={**child_env(), "TERM": "xterm-256color", "COLUMNS": "100", "LINES": "30"},
        stdin=tty,
        stdout=tty,
        stderr=tty,
        start_new_session=True,
    )
    screen = _Screen()
    reader = threading.Thread(target=screen.drain, args=(main,), daemon=True)
    reader.start()
    try:
        with _operator(show) as session, Stagehand(session, ShowKeys(show.show_id)):
            first = _run_file(show, lambda r: "console" in r.children).children["console"]
            shown_before = screen.size()
            os.kill(first.pid, signal.SIGKILL)
            again = _run_file(show, lambda r: r.children["console"].pid != first.pid)
            assert _write_one(session, show, "一").state == "done"  # the show never noticed
            _wait_landed(session, show)  # else `q` asks first (a vehicle flies)
            screen.wait_for(MOUSE_ON, after=shown_before)  # the new console took the terminal...
            time.sleep(1.0)  # ...and reads its keys: quit it with its own
            os.write(main, b"q")
            deadline = time.monotonic() + 20.0
            while again.children["console"].alive():
                assert time.monotonic() < deadline, "the console did not quit"
                time.sleep(0.1)
            assert up.poll() is None  # quitting the viewer left the show running
            assert _write_one(session, show, "二").state == "done"
        children = RunFile.load(run_file_path(show.database_path))
        assert children is not None
        _down(path)
        assert up.wait(timeout=30) == 0
    finally:
        if up.poll() is None:  # failed midway: the children outlive a killed `up` by design
            up.kill()
            subprocess.run(skyquill_argv("down", str(path)), env=child_env(), timeout=60)
        os.close(tty)
    log = (show.database_path.parent / "logs" / "up.log").read_text()
    assert "console exited (killed by signal 9); reopening it" in log, log[-3000:]
    assert "the show keeps running" in log and "killing" not in log
    assert not [r for name, r in children.children.items() if r.alive()]


MOUSE_ON = b"\x1b[?1000h"
"""What a console (Textual) writes when it takes the terminal's input (mouse reporting on; a
console reopened in the same terminal does not switch to the alternate screen again)."""


class _Screen:
    """What ``up``'s terminal showed (its pseudo-terminal, drained so nothing blocks)."""

    def __init__(self) -> None:
        self.shown = bytearray()
        self._lock = threading.Lock()

    def drain(self, fd: int) -> None:
        try:
            while chunk := os.read(fd, 65536):
                with self._lock:
                    self.shown += chunk
        except OSError:
            pass

    def size(self) -> int:
        with self._lock:
            return len(self.shown)

    def wait_for(self, marker: bytes, *, after: int, timeout_s: float = 60.0) -> None:
        """Until ``marker`` is shown past the first ``after`` bytes."""
        deadline = time.monotonic() + timeout_s
        while True:
            with self._lock:
                if marker in self.shown[after:]:
                    return
            assert time.monotonic() < deadline, f"{marker!r} was not shown"
            time.sleep(0.1)


def test_a_killed_up_leaves_the_show_running_and_a_new_up_adopts_it(tmp_path: Path) -> None:
    path, show = _solo(tmp_path)
    argv = skyquill_argv("up", str(path), "--headless", "--no-kiosk")
    first = subprocess.Popen(argv, env=child_env(), stderr=subprocess.DEVNULL)
    second: subprocess.Popen[str] | None = None
    try:
        with _operator(show) as session, Stagehand(session, ShowKeys(show.show_id)):
            assert _write_one(session, show, "一").state == "done"
            before = _run_file(show, lambda r: len(r.children) == 3).children
            first.kill()  # SIGKILL: no chance to stop anything
            first.wait()
            assert all(record.alive() for record in before.values())
            assert _write_one(session, show, "L").state == "done"  # router and all run on
            second = subprocess.Popen(argv, env=child_env(), stderr=subprocess.PIPE, text=True)
            after = _run_file(show, lambda r: r.up is not None and r.up.pid == second.pid)
            assert after.children == before  # the same processes, adopted
            os.kill(before["router"].pid, signal.SIGKILL)  # and supervised again
            _run_file(show, lambda r: r.children["router"].pid != before["router"].pid)
            assert _write_one(session, show, "十").state == "done"
        assert "stopped" in _down(path)
        _, stderr = second.communicate(timeout=30)
    finally:
        leftover = False
        for process in (first, second):
            if process is not None and process.poll() is None:
                process.kill()
                leftover = True
        if leftover:  # the children outlive a killed `up` by design: stop them for good
            subprocess.run(skyquill_argv("down", str(path)), env=child_env(), timeout=60)
    assert second.returncode == 0, stderr
    assert "adopted router" in stderr and "killing" not in stderr
    assert not [r for r in before.values() if r.alive()]


def test_an_estop_of_the_whole_fleet_is_undone_by_the_consoles_path(live: LiveShow) -> None:
    """E-STOP of every vehicle while they write, then the console's documented way back (reset
    every fault, release all, resume; the crew's fresh sheets): every vehicle writes again
    (before, each faulted at its next take-off: its backend stayed in ``estop``)."""
    vehicles = [v.id for v in live.run.show.vehicles]
    job_ids = live.submit(["大", "木", "人"])
    live.wait_until_all_writing(job_ids)
    live.command(OperatorCommand(command="estop", reason="test"))

    def states() -> dict[str, tuple[str, bool]]:
        return {v.vehicle_id: (v.state, v.held) for v in live.snapshot().vehicles}

    deadline = time.monotonic() + 20.0
    while set(states().values()) != {("fault", True)}:
        assert time.monotonic() < deadline, states()
        time.sleep(0.1)
    for vid in vehicles:
        live.command(OperatorCommand(command="clear_fault", vehicle_id=vid))
    while set(states().values()) != {("landed", True)}:
        assert time.monotonic() < deadline + 20.0, states()
        time.sleep(0.1)
    live.command(OperatorCommand(command="release_all"))
    live.command(OperatorCommand(command="resume"))
    assert [j.state for j in live.wait(job_ids)] == ["done"] * 3  # back in the queue, written
    again = live.submit(["上", "下", "中"])
    assert {j.vehicle_id for j in live.wait(again)} == set(vehicles)  # each flies again
    live.check_written_once()

"""A whole show run from one Python process: the demo command and the multi-process tests.

:func:`derived_show` writes a copy of a show file on a free loopback port with its own storage;
:class:`ShowRun` supervises the router, the orchestrator and the agents as child processes;
:func:`submit_texts` and :func:`wait_for_jobs` talk to the orchestrator like any client;
:class:`Stagehand` puts a fresh sheet on boards left half-written, as the show's crew would.
"""

from __future__ import annotations

import functools
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import Any

from bus.keys import ShowKeys
from bus.messages import (
    CommandReply,
    ErrorInfo,
    JobState,
    OperatorCommand,
    ShowSnapshot,
    SubmitReply,
    SubmitRequest,
)
from bus.rpc import NoReplyError, RemoteError, query_one
from bus.session import Session, free_tcp_endpoint, open_session
from cli.fleets import split_fleets
from cli.supervisor import ChildSpec, RestartPolicy, Supervisor, child_env, show_children
from showfile import Show, dump_show, load_show
from trust.settings import ensure_show_keys, session_settings

FINAL_STATES = frozenset({"done", "failed", "cancelled", "rejected"})


def derived_show(
    source: Path,
    out_dir: Path,
    *,
    time_scale: float | None = None,
    **updates: Any,
) -> tuple[Path, Show]:
    """A copy of ``source`` on a free loopback port, storing under ``out_dir``; returns its path.

    The copy is written in ``out_dir`` and its paths are relative to its own folder (where a show
    file's relative paths start, ``showfile/paths.py``): ``out_dir`` keeps everything together."""
    show = load_show(source)
    endpoint = free_tcp_endpoint()
    zenoh = show.zenoh.model_copy(update={"router_listen": (endpoint,), "connect": (endpoint,)})
    storage = show.storage.model_copy(
        update={"database": Path("show.sqlite3"), "recordings_dir": Path("recordings")}
    )
    security = show.security.model_copy(update={"keys_dir": Path("keys")})
    changes: dict[str, Any] = {
        "zenoh": zenoh,
        "storage": storage,
        "security": security,
        **updates,
    }
    if time_scale is not None:
        changes["time_scale"] = time_scale
    derived = show.model_copy(update=changes)
    path = out_dir / Path(source).name
    dump_show(derived, path)
    return path, load_show(path)


@dataclass
class ShowRun:
    """The show's processes, router included, supervised from a thread of this process; a
    context manager that stops everything (the children also die with this process)."""

    show_path: Path
    """The show file the children read."""
    show: Show
    """The same show, loaded."""
    log_dir: Path | None = None
    """Children's output goes to ``<name>.log`` files here (None: inherited stderr)."""
    say: Callable[[str], None] | None = None
    """Where supervisor messages go (default: stderr)."""
    policy: RestartPolicy | None = None
    """Restart backoff."""
    adjust: Callable[[ChildSpec], ChildSpec] | None = None
    """Changes each child's spec before it starts (a benchmark runs some under a tracer)."""

    def __post_init__(self) -> None:
        agents, fleets = split_fleets(self.show, [v.id for v in self.show.vehicles])
        self.specs: list[ChildSpec] = show_children(
            self.show_path,
            agents,
            fleets=fleets,
            mavlink_sim=self.show.mavlink_sim.enabled,
            log_dir=self.log_dir,
        )
        if self.adjust is not None:
            self.specs = [self.adjust(spec) for spec in self.specs]
        self.supervisor = Supervisor(self.specs, env=child_env(), say=self.say, policy=self.policy)
        self._stop = threading.Event()
        self._watcher: threading.Thread | None = None
        self.keys = ShowKeys(self.show.show_id)

    def __enter__(self) -> ShowRun:
        ensure_show_keys(self.show)
        try:
            self.supervisor.start()
        except BaseException:
            self.supervisor.stop()
            raise
        self._watcher = threading.Thread(target=self._watch, daemon=True)
        self._watcher.start()
        return self

    def _watch(self) -> None:
        self.supervisor.run_until(self._stop.is_set, period_s=0.05)

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self._stop.set()
        if self._watcher is not None:
            self._watcher.join()
        if self.simulated:
            self.supervisor.hurry()  # nothing real flies: no landing to wait for
        self.supervisor.stop()

    @property
    def simulated(self) -> bool:
        """Every vehicle is simulated: in process, or by the show's own MAVLink simulator."""
        sim = self.show.mavlink_sim.enabled
        return all(v.backend == "sim" or sim for v in self.show.vehicles)

    def client(self, open_timeout_s: float = 30.0) -> Session:
        """An operator's client session on the show's router (use it in a ``with`` block);
        waits up to ``open_timeout_s`` for the router process to listen."""
        settings = session_settings(self.show, "operator")
        return open_session(settings, role="client", open_timeout_s=open_timeout_s)


def submit_texts(
    session: Session, keys: ShowKeys, texts: Sequence[str], *, timeout_s: float = 30.0
) -> list[SubmitReply]:
    """Submit each text, retrying while the orchestrator is not answering yet."""
    replies = []
    for text in texts:
        request = SubmitRequest(text=text, client_id="demo")
        replies.append(_retry(functools.partial(_submit, session, keys, request), timeout_s))
    return replies


def _submit(session: Session, keys: ShowKeys, request: SubmitRequest) -> SubmitReply:
    reply = query_one(session, keys.submit, request, SubmitReply, timeout_s=5.0)
    if not reply.ok:
        raise RemoteError(reply.error or ErrorInfo(code="refused", message="submission refused"))
    return reply


def _retry(call: Callable[[], Any], timeout_s: float) -> Any:
    deadline = time.monotonic() + timeout_s
    while True:
        try:
            return call()
        except NoReplyError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.2)


def snapshot(session: Session, keys: ShowKeys, *, timeout_s: float = 5.0) -> ShowSnapshot:
    """The orchestrator's current view of the show."""
    return query_one(session, keys.snapshot, None, ShowSnapshot, timeout_s=timeout_s)


class Stagehand:
    """The show's crew, as at the Airshow: replaces the sheet of every board a lost or stopped
    vehicle left half-written, or whose character a visitor takes away (``sheets:
    per_character``), with the operator's ``fresh_sheet``, and puts a fresh battery in every
    vehicle waiting for one (``battery_swapped``: a simulated vehicle's pack is full again); a
    thread, for tests, benchmarks and the demo. ``replaced`` lists the boards in order,
    ``swapped`` the vehicles. Without the batteries a soak at time scale 4 stood still after
    10 minutes, all four vehicles waiting for a swap (issue 35's hour)."""

    def __init__(self, session: Session, keys: ShowKeys, *, period_s: float = 0.3) -> None:
        self._session, self._keys, self._period_s = session, keys, period_s
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="stagehand", daemon=True)
        self.replaced: list[str] = []
        self.swapped: list[str] = []

    def __enter__(self) -> Stagehand:
        self._thread.start()
        return self

    def __exit__(self, *_: object) -> None:
        self._stop.set()
        self._thread.join()

    def _run(self) -> None:
        while not self._stop.wait(self._period_s):
            try:
                shown = snapshot(self._session, self._keys, timeout_s=2.0)
                for board_id in _crews_boards(shown):
                    if self._ask(OperatorCommand(command="fresh_sheet", board_id=board_id,
                                                 operator="stagehand")):  # fmt: skip
                        self.replaced.append(board_id)
                for vehicle in shown.vehicles:
                    if vehicle.state == "battery_swap" and self._ask(OperatorCommand(
                        command="battery_swapped", vehicle_id=vehicle.vehicle_id,
                        operator="stagehand",
                    )):  # fmt: skip
                        self.swapped.append(vehicle.vehicle_id)
            except (NoReplyError, RemoteError):
                continue  # the orchestrator is restarting

    def _ask(self, command: OperatorCommand) -> bool:
        """Send one crew command; whether the orchestrator took it."""
        return query_one(self._session, self._keys.command, command, CommandReply).ok


def wait_for_jobs(
    session: Session,
    keys: ShowKeys,
    job_ids: Sequence[str],
    *,
    timeout_s: float,
    on_change: Callable[[list[JobState]], None] | None = None,
    period_s: float = 0.5,
) -> list[JobState]:
    """Poll the snapshot until every job is final; the jobs in ``job_ids`` order.

    Raises TimeoutError with the jobs' last states when ``timeout_s`` passes first.
    """
    deadline = time.monotonic() + timeout_s
    wanted = list(job_ids)
    last: dict[str, JobState] = {}
    while True:
        try:
            snap = snapshot(session, keys)
        except NoReplyError:
            snap = None  # the orchestrator is restarting
        if snap is not None:
            jobs = {job.job_id: job for job in snap.jobs}
            current = {job_id: jobs[job_id] for job_id in wanted if job_id in jobs}
            if on_change is not None and current != last:
                on_change([current[j] for j in wanted if j in current])
            last = current
            if len(current) == len(wanted) and all(
                job.state in FINAL_STATES for job in current.values()
            ):
                return [current[j] for j in wanted]
        if time.monotonic() > deadline:
            states = {j: (last[j].state if j in last else "unknown") for j in wanted}
            raise TimeoutError(f"jobs not finished after {timeout_s:.0f} s: {states}")
        time.sleep(period_s)


def _crews_boards(shown: ShowSnapshot) -> list[str]:
    """The boards waiting for a sheet that a crew changes by routine: not those whose job waits
    for a lost vehicle (``job_waits``: the operator's call, after looking at the board)."""
    boards = {v.vehicle_id: v.board_id for v in shown.vehicles}
    operators = {boards.get(a.vehicle_id or "") for a in shown.alerts if a.kind == "job_waits"}
    return [b for b in shown.dirty_boards if b not in operators]

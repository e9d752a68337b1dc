"""One show across three hosts: Linux network namespaces joined by impaired links.

The venue of ``shows/venue-multihost.yaml``: a ground station (its router, the orchestrator) and
two companion hosts (``rack1``: a router and agents uav1, uav2; ``rack2``: a router and uav3),
each a network namespace with its own loopback, linked to the ground station by a link that
delays every packet 50 ms each way and drops 5 % (``test_multihost_venue.py``). Each host runs
``skyquill up SHOW --host NAME`` unchanged; every link is mutual TLS, and each router enforces
the generated access control. The test's client lives on the ground station: this file run as
``observe`` submits, answers snapshots and records events and ink, over pipes and files.

Checked: the show writes through delay and loss; a 10 s partition of the companion host whose
vehicle is writing has that vehicle taken as lost within ``lost_after_s``, but its job waits for
it (the write fence, ``bus/fence.py``): cut off, it finishes the character, and once healed its
report makes the job ``done``, written by it alone; nobody else is given the job meanwhile;
every acknowledged submission is done, written completely exactly once; every host stops with
no SIGKILL. Skipped
with the reason where namespaces are unavailable.
"""

from __future__ import annotations

import contextlib
import json
import sqlite3
import subprocess
import sys
import threading
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

import pytest
from test_multihost_venue import Venue, venue_fixture  # noqa: F401 (the fixture "venue")

ROOT = Path(__file__).resolve().parent.parent
VENUE = ROOT / "shows" / "venue-multihost.yaml"
TIME_SCALE = 6.0
PARTITION_S = 10.0
JOB_TIMEOUT_S = 60.0

pytestmark = [pytest.mark.multiprocess, pytest.mark.slow, pytest.mark.timeout(240)]


# --- the client on the ground station -----------------------------------------------------------


class Observer:
    """This file run as ``observe`` inside the ground namespace: one operator session."""

    def __init__(self, venue: Venue, show_path: Path, out: Path) -> None:
        from cli.supervisor import child_env

        self.out = out
        argv = venue.exec_argv("ground", sys.executable, __file__, "observe", str(show_path))
        self.process = subprocess.Popen(
            [*argv, str(out)],
            env=child_env(),
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=(out / "observer.log").open("wb"),
            text=True,
        )
        self.lock = threading.Lock()
        self.acknowledged: list[str] = []

    def ask(self, request: dict[str, Any]) -> dict[str, Any]:
        with self.lock:
            stdin, stdout = self.process.stdin, self.process.stdout
            assert stdin is not None and stdout is not None
            stdin.write(json.dumps(request) + "\n")
            stdin.flush()
            line = stdout.readline()
        assert line, f"the observer died: {(self.out / 'observer.log').read_text()[-2000:]}"
        reply: dict[str, Any] = json.loads(line)
        return reply

    def submit(self, texts: list[str]) -> list[str]:
        ids = [str(self.ask({"submit": text})["job_id"]) for text in texts]
        self.acknowledged.extend(ids)
        return ids

    def snapshot(self) -> dict[str, Any]:
        return self.ask({"snapshot": True})

    def records(self, name: str) -> list[dict[str, Any]]:
        path = self.out / f"{name}.jsonl"
        if not path.exists():
            return []
        lines = path.read_text(encoding="utf-8").splitlines()
        return [json.loads(line) for line in lines if line.endswith("}")]

    def close(self) -> None:
        if self.process.stdin is not None:
            self.process.stdin.close()
        try:
            self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.process.kill()


def observe(show_path: str, out_dir: str) -> None:
    """The client: answers requests on stdin, appends events and ink to files in ``out_dir``."""
    from bus.keys import ShowKeys
    from bus.messages import Event, Telemetry
    from bus.pubsub import subscribe
    from bus.session import open_session
    from cli.showrun import Stagehand
    from showfile import load_show
    from trust.settings import session_settings

    show = load_show(Path(show_path))
    keys = ShowKeys(show.show_id)
    out = Path(out_dir)
    settings = session_settings(show, "operator")
    with (
        open_session(settings, role="client", open_timeout_s=60.0) as session,
        (out / "events.jsonl").open("a", encoding="utf-8") as events,
        (out / "ink.jsonl").open("a", encoding="utf-8") as ink,
        Stagehand(session, keys),
    ):
        lock = threading.Lock()

        def append(stream: IO[str], record: dict[str, Any]) -> None:
            with lock:
                stream.write(json.dumps(record) + "\n")
                stream.flush()

        def on_event(_key: str, e: Event) -> None:
            record = {"time_s": e.time_s, "kind": e.kind, "vehicle_id": e.vehicle_id}
            append(events, record | {"job_id": e.job_id})

        def on_telemetry(_key: str, t: Telemetry) -> None:
            if t.pen_down and t.job_id is not None:
                append(ink, {"at_s": time.time(), "vehicle_id": t.vehicle_id, "job_id": t.job_id})

        subscribe(session, keys.events, Event, on_event)
        subscribe(session, keys.telemetry_all, Telemetry, on_telemetry)
        for line in sys.stdin:
            print(_answer(session, keys, json.loads(line)), flush=True)


def _answer(session: Any, keys: Any, request: dict[str, Any]) -> str:
    """A submission, acknowledged (retried under one idempotency key while the orchestrator is
    busy or away), or the orchestrator's snapshot (empty while it is not up)."""
    from bus.codec import encode
    from bus.messages import SubmitReply, SubmitRequest
    from bus.rpc import NoReplyError, RemoteError, query_one
    from cli.showrun import snapshot

    if "submit" not in request:
        try:
            return encode(snapshot(session, keys, timeout_s=5.0)).decode()
        except (NoReplyError, RemoteError):
            return json.dumps({"jobs": [], "vehicles": []})
    submission = SubmitRequest(
        text=request["submit"], client_id="multihost", idempotency_key=uuid.uuid4().hex
    )
    deadline = time.monotonic() + 60.0
    while True:
        try:
            reply = query_one(session, keys.submit, submission, SubmitReply, timeout_s=5.0)
            assert reply.ok, f"{submission.text} refused: {reply.error}"
            return json.dumps({"job_id": reply.job_id})
        except (NoReplyError, RemoteError):
            pass
        assert time.monotonic() < deadline, f"{submission.text} not acknowledged in 60 s"
        time.sleep(0.5)


# --- the show ------------------------------------------------------------------------------------


@dataclass
class Hosts:
    venue: Venue
    show_path: Path
    out: Path
    ups: dict[str, subprocess.Popen[bytes]] = field(default_factory=dict)

    def up(self, host: str) -> None:
        from cli.supervisor import child_env, skyquill_argv

        argv = skyquill_argv("up", str(self.show_path), "--host", host, "--headless", "--no-kiosk")
        self.ups[host] = subprocess.Popen(
            self.venue.exec_argv(host, *argv),
            env=child_env(),
            stdout=subprocess.DEVNULL,
            stderr=(self.out / f"up-{host}.err").open("wb"),
        )

    def down(self, host: str) -> str:
        from cli.supervisor import child_env, skyquill_argv

        argv = skyquill_argv("down", str(self.show_path), "--host", host)
        done = subprocess.run(
            self.venue.exec_argv(host, *argv),
            env=child_env(),
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert done.returncode == 0, done.stderr
        self.ups[host].wait(timeout=30)
        return (self.out / "logs" / host / "up.log").read_text(encoding="utf-8")


def _venue_show(out: Path) -> tuple[Path, Any]:
    from showfile import dump_show, load_show
    from trust.settings import ensure_show_keys

    show = load_show(VENUE)
    storage = show.storage.model_copy(
        update={"database": out / "show.sqlite3", "recordings_dir": out / "recordings"}
    )
    security = show.security.model_copy(update={"keys_dir": out / "keys"})
    changes = {"storage": storage, "security": security, "time_scale": TIME_SCALE}
    path = out / VENUE.name
    dump_show(show.model_copy(update=changes), path)
    show = load_show(path)
    ensure_show_keys(show)  # as the ground station's `up` would; the companions copy theirs
    return path, show


def _wait(what: str, timeout_s: float, check: Any) -> Any:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        found = check()
        if found:
            return found
        time.sleep(0.2)
    raise AssertionError(f"{what} not within {timeout_s:.0f} s")


def _jobs(observer: Observer) -> dict[str, dict[str, Any]]:
    return {job["job_id"]: job for job in observer.snapshot()["jobs"]}


def _ready(observer: Observer, vehicle_ids: list[str]) -> bool:
    vehicles = {v["vehicle_id"]: v for v in observer.snapshot()["vehicles"]}
    return all(
        vid in vehicles and vehicles[vid]["alive"] and vehicles[vid]["state"] in ("idle", "landed")
        for vid in vehicle_ids
    )


def _all_done(observer: Observer, job_ids: list[str]) -> bool:
    jobs = _jobs(observer)
    final = ("done", "failed", "cancelled", "rejected")
    if not all(j in jobs and jobs[j]["state"] in final for j in job_ids):
        return False
    assert [jobs[j]["state"] for j in job_ids] == ["done"] * len(job_ids), jobs
    return True


def test_one_show_across_three_hosts_writes_through_loss_and_a_partition(
    venue: Venue, tmp_path: Path
) -> None:
    show_path, show = _venue_show(tmp_path)
    hosts = Hosts(venue, show_path, tmp_path)
    host_of = {vid: name for name, h in show.zenoh.hosts.items() for vid in h.vehicles}
    vehicle_ids = list(host_of)
    observer: Observer | None = None
    try:
        for host in ("ground", "rack1", "rack2"):
            hosts.up(host)
        observer = Observer(venue, show_path, tmp_path)
        _wait("every vehicle ready", 120.0, lambda: _ready(observer, vehicle_ids))
        started = time.monotonic()
        first = observer.submit(["一", "L", "十"])  # 50 ms delay, 5 % loss on every link
        _wait("the first three written", JOB_TIMEOUT_S, lambda: _all_done(observer, first))
        print(f"\n3 characters across hosts in {time.monotonic() - started:.1f} s")

        (job_id,) = observer.submit(["马"])
        # Cut once the brush is down: a job ``writing`` at the orchestrator has its ready report
        # stored, but its vehicle may still wait for the acknowledgement, and one unheard for
        # ``unheard_before_writing_s`` (10 s) before writing rightly gives the job up.
        inking = _wait(
            "马 inking",
            JOB_TIMEOUT_S,
            lambda: [r for r in observer.records("ink") if r["job_id"] == job_id],
        )
        victim = str(inking[0]["vehicle_id"])
        cut_host = host_of[victim]
        cut_at = time.time()
        venue.partition(cut_host, cut=True)
        lost = _wait(
            f"{victim} lost",
            10.0,
            lambda: [
                e
                for e in observer.records("events")
                if e["kind"] == "vehicle_lost"
                and e["vehicle_id"] == victim
                and e["time_s"] > cut_at
            ],
        )
        lost_after_s = lost[0]["time_s"] - cut_at
        print(f"{cut_host} cut off: {victim} lost after {lost_after_s:.2f} s")
        assert lost_after_s <= show.policy.lost_after_s + 0.5
        time.sleep(max(0.0, cut_at + PARTITION_S - time.time()))
        venue.partition(cut_host, cut=False)
        healed_at = time.time()
        _wait("马 done", JOB_TIMEOUT_S, lambda: _all_done(observer, [job_id]))
        print(f"马 done {time.time() - healed_at:.2f} s after the partition healed")
        job = _jobs(observer)[job_id]
        said = [e for e in observer.records("events") if e.get("job_id") == job_id]
        victim_log = (tmp_path / "logs" / cut_host / f"{victim}.log").read_text()
        assert job["vehicle_id"] == victim and job["attempts"] == 1, (  # nobody else had it
            job,
            said,
            victim_log[-3000:],
        )
        _wait(f"{victim} back", 30.0, lambda: _ready(observer, [victim]))
        kinds = [e["kind"] for e in observer.records("events") if e.get("job_id") == job_id]
        assert "board_dirty" not in kinds and "job_waits" not in kinds, kinds  # back in its hold
        _check_written_once(show, observer)
        victim_log = (tmp_path / "logs" / cut_host / f"{victim}.log").read_text()
        assert f"gave job {job_id} up: " not in victim_log
        for host in ("rack1", "rack2", "ground"):  # companions first: the ground router last
            log = hosts.down(host)
            assert "SIGKILLed: none" in log, log
    finally:
        if observer is not None:
            observer.close()
        for host, up in hosts.ups.items():
            if up.poll() is None:
                with contextlib.suppress(AssertionError, subprocess.TimeoutExpired):
                    hosts.down(host)


def _check_written_once(show: Any, observer: Observer) -> None:
    """Every acknowledged job done in the store, one complete job folder each."""
    ids = observer.acknowledged
    stored = sqlite3.connect(f"file:{show.database_path}?mode=ro", uri=True)
    try:
        states = dict(stored.execute("SELECT job_id, state FROM jobs").fetchall())
    finally:
        stored.close()
    assert {j: states.get(j) for j in ids} == dict.fromkeys(ids, "done")
    folders = [p.name for p in (show.database_path.parent / "jobs").iterdir()]
    for job_id in ids:
        assert len([n for n in folders if n.startswith(f"{job_id}-")]) == 1, job_id


if __name__ == "__main__" and sys.argv[1:2] == ["observe"]:
    sys.path.insert(0, str(ROOT))
    observe(sys.argv[2], sys.argv[3])

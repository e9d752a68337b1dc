"""Helpers of the kiosk tests (no tests here): a fake orchestrator on real Zenoh, an HTTP client.

The fake answers ``submit`` and ``snapshot`` like the orchestrator (bus/keys.py) and publishes
``jobs/<id>`` JobState when a test says so, so the kiosk is tested over the real bus.
"""

from __future__ import annotations

import http.client
import http.cookiejar
import itertools
import json
import threading
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

from bus.keys import ShowKeys
from bus.messages import (
    ErrorInfo,
    JobMetrics,
    JobState,
    ShowSnapshot,
    SubmitReply,
    SubmitRequest,
)
from bus.pubsub import publish
from bus.rpc import serve
from bus.session import Session

WAIT_S = 10.0
"""Upper bound for anything to arrive on loopback; never a timing assertion."""


@dataclass
class FakeOrchestrator:
    """Answers ``submit`` and ``snapshot``; publishes job states on request."""

    session: Session
    keys: ShowKeys
    mode: str = "accept"
    """``accept`` or an error code to reply with (e.g. ``queue_full``)."""
    requests: list[SubmitRequest] = field(default_factory=list)
    jobs: dict[str, JobState] = field(default_factory=dict)
    by_key: dict[tuple[str, str], str] = field(default_factory=dict)
    """(client id, idempotency key) -> job id, as the orchestrator keeps it."""
    thawed: threading.Event = field(default_factory=threading.Event)
    """Cleared: the fake is hung (submissions wait, no fleet snapshots); set: it runs."""
    _queryables: list[Any] = field(default_factory=list)
    _lock: threading.Lock = field(default_factory=threading.Lock)
    _stop: threading.Event = field(default_factory=threading.Event)

    def start(self) -> FakeOrchestrator:
        self.thawed.set()
        self._queryables = [
            serve(self.session, self.keys.submit_as("kiosk"), SubmitRequest, self._on_submit),
            serve(self.session, self.keys.snapshot, None, self._on_snapshot),
        ]
        self._stop.clear()
        threading.Thread(target=self._fleet_loop, daemon=True).start()
        return self

    def stop(self) -> None:
        self._stop.set()
        for q in self._queryables:
            q.undeclare()
        self._queryables = []

    def _fleet_loop(self) -> None:
        """Publish the 1 Hz fleet snapshot like the orchestrator (not while hung or stopped)."""
        while not self._stop.wait(1.0):
            if self.thawed.is_set():
                publish(self.session, self.keys.fleet, self._on_snapshot(None))

    def _on_submit(self, request: SubmitRequest) -> SubmitReply:
        self.thawed.wait()  # a hung orchestrator answers late (after the kiosk gave up waiting)
        with self._lock:
            self.requests.append(request)
            if self.mode != "accept":
                return SubmitReply(ok=False, error=ErrorInfo(code=self.mode, message=self.mode))
            key = request.idempotency_key
            first = self.by_key.get((request.client_id, key)) if key else None
            if first is not None:
                old = self.jobs[first]
                return SubmitReply(
                    ok=True, job_id=first, state=old.state,
                    queue_position=old.queue_position, eta_s=old.eta_s,
                )  # fmt: skip
            job_id = f"job-{len(self.requests)}"
            if key:
                self.by_key[(request.client_id, key)] = job_id
            queued = [j for j in self.jobs.values() if j.state == "queued"]
            now = time.time()
            state = JobState(
                job_id=job_id,
                state="queued",
                label=request.text or "drawing",
                kind="text" if request.text else "strokes",
                client_id=request.client_id,
                created_at_s=now,
                updated_at_s=now,
                queue_position=len(queued) + 1,
                eta_s=30.0 * len(queued),
            )
            self.jobs[job_id] = state
        return SubmitReply(
            ok=True,
            job_id=job_id,
            state="queued",
            queue_position=state.queue_position,
            eta_s=state.eta_s,
        )

    def _on_snapshot(self, _request: None) -> ShowSnapshot:
        with self._lock:
            jobs = list(self.jobs.values())
        return ShowSnapshot(
            show_id=self.keys.show_id, time_s=time.time(), queue_paused=False, jobs=jobs,
            vehicles=[],
        )  # fmt: skip

    def set_state(self, job_id: str, state: str, **changes: Any) -> JobState:
        """Change a job and publish it on ``jobs/<id>`` like the orchestrator does."""
        with self._lock:
            old = self.jobs.get(job_id) or JobState(
                job_id=job_id, state="queued", label="?", kind="text", client_id="cli",
                created_at_s=time.time(), updated_at_s=time.time(),
            )  # fmt: skip
            fields = {f: getattr(old, f) for f in old.__struct_fields__}
            fields.update(changes, state=state, updated_at_s=time.time())
            new = JobState(**fields)
            self.jobs[job_id] = new
        publish(self.session, self.keys.job(job_id), new)
        return new


def done_metrics() -> JobMetrics:
    return JobMetrics(
        rmse_pen_down_m=0.012, rmse_m=0.02, max_error_m=0.05, iou=0.8, duration_s=21.0
    )


@dataclass
class Reply:
    status: int
    body: dict[str, Any]
    headers: dict[str, str]


_addresses = (f"127.1.{n // 250}.{n % 250 + 1}" for n in itertools.count())


def fresh_address() -> str:
    """A loopback address no other visitor of this test run connects from (Linux: 127/8)."""
    return next(_addresses)


class _FromAddress(urllib.request.HTTPHandler):
    """Connects from a chosen local address, so each visitor is its own client address."""

    def __init__(self, source: str) -> None:
        super().__init__()
        self.source = source

    def http_open(self, req: urllib.request.Request) -> http.client.HTTPResponse:
        return self.do_open(http.client.HTTPConnection, req, source_address=(self.source, 0))


class Browser:
    """An HTTP client with its own cookie jar (one visitor) and its own address.

    ``source``: the local address it connects from (default: a fresh loopback address, as the
    kiosk limits each address); ``forwarded_for``: an ``X-Forwarded-For`` header to send.
    """

    def __init__(
        self, base_url: str, *, source: str | None = None, forwarded_for: str | None = None
    ) -> None:
        self.base_url = base_url.rstrip("/")
        self.source = source or fresh_address()
        self.forwarded_for = forwarded_for
        self.cookies = http.cookiejar.CookieJar()
        self._opener = urllib.request.build_opener(
            _FromAddress(self.source), urllib.request.HTTPCookieProcessor(self.cookies)
        )

    def request(self, method: str, path: str, body: bytes | dict[str, Any] | None = None) -> Reply:
        data = json.dumps(body).encode() if isinstance(body, dict) else body
        req = urllib.request.Request(self.base_url + path, data=data, method=method)
        if data is not None:
            req.add_header("Content-Type", "application/json")
        if self.forwarded_for is not None:
            req.add_header("X-Forwarded-For", self.forwarded_for)
        try:
            with self._opener.open(req, timeout=WAIT_S) as resp:
                return Reply(resp.status, json.loads(resp.read()), dict(resp.headers))
        except urllib.error.HTTPError as err:
            with err:
                return Reply(err.code, json.loads(err.read()), dict(err.headers))

    def request_raw(self, path: str) -> tuple[int, str, bytes]:
        """GET a non-JSON resource: status, content type, body."""
        try:
            with self._opener.open(self.base_url + path, timeout=WAIT_S) as resp:
                return resp.status, resp.headers["content-type"], resp.read()
        except urllib.error.HTTPError as err:
            with err:
                return err.code, err.headers["content-type"], err.read()

    def post(self, path: str, body: bytes | dict[str, Any] | None) -> Reply:
        return self.request("POST", path, body)

    def get(self, path: str) -> Reply:
        return self.request("GET", path)


def sse_events(base_url: str, path: str) -> Iterator[tuple[str, dict[str, Any]]]:
    """``(event, data)`` of a server-sent event stream until the server ends it."""
    host_port = base_url.split("//", 1)[1].rstrip("/")
    conn = http.client.HTTPConnection(host_port, timeout=WAIT_S)
    try:
        conn.request("GET", path, headers={"Accept": "text/event-stream"})
        resp = conn.getresponse()
        assert resp.status == 200, resp.read()
        assert resp.headers["content-type"].startswith("text/event-stream")
        event, data = "message", ""
        while line := resp.readline():
            text = line.decode().rstrip("\n")
            if text.startswith("event: "):
                event = text[7:]
            elif text.startswith("data: "):
                data += text[6:]
            elif text == "" and data:
                yield event, json.loads(data)
                event, data = "message", ""
    finally:
        conn.close()


def drawing(strokes: list[list[list[float]]]) -> dict[str, Any]:
    """A strokes document as the page sends it (canvas pixels, y down)."""
    return {
        "strokes": {
            "units": "px",
            "y_axis": "down",
            "canvas": {"width": 300, "height": 300},
            "strokes": strokes,
        }
    }


L_DRAWING = drawing(
    [[[100.0, 50.0, 0.0, 0.5], [100.0, 150.0, 0.2, 0.6], [100.0, 250.0, 0.4, 0.6],
      [180.0, 250.0, 0.6, 0.5], [240.0, 250.0, 0.8, 0.4]]]
)  # fmt: skip

"""The kiosk web application: one page and a small JSON API (Starlette).

Routes
    GET  /                          the page
    GET  /api/config                limits the page needs (text length, strokes, points, area)
    POST /api/preview               ``{"text": ...}`` or ``{"strokes": {...}}`` -> planned path
    POST /api/submit                same body -> job id, token, queue place, ETA, planned path
    GET  /api/jobs/{id}?token=T     the job's state (only with the token returned on submit)
    GET  /api/jobs/{id}/events?token=T   server-sent events of the job's state until it is final

Every refusal is ``{"ok": false, "error": {"code": ..., "message": ...}}`` with a message for the
public; nothing a visitor sends can stop the service.
"""

from __future__ import annotations

import contextlib
import logging
import time
from collections.abc import AsyncIterator, Callable
from pathlib import Path
from typing import Any

from starlette.applications import Starlette
from starlette.concurrency import run_in_threadpool
from starlette.middleware import Middleware
from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, Response, StreamingResponse
from starlette.routing import Mount, Route
from starlette.staticfiles import StaticFiles

from bus.messages import JobState, SubmitReply, SubmitRequest
from kiosk import wording
from kiosk.errors import RejectedError
from kiosk.http import Client, SecurityHeaders, identify, read_capped, remember
from kiosk.jobs import job_view
from kiosk.limits import Submission, check_submission, decode_json_body
from kiosk.link import OrchestratorLink, OrchestratorUnavailableError
from kiosk.ratelimit import SlidingWindowLimiter
from kiosk.settings import KioskSettings
from kiosk.sse import job_events

log = logging.getLogger(__name__)

STATIC_DIR = Path(__file__).parent / "static"
MAX_STREAMS = 1_000
"""Open status streams the kiosk serves at once."""

Previewer = Callable[[Submission], dict[str, Any]]
"""Plans a checked submission and returns the preview (raises RejectedError if it cannot)."""


class Kiosk:
    """The state behind the routes: settings, limiters, the bus link and the planner preview."""

    def __init__(
        self,
        settings: KioskSettings,
        link: OrchestratorLink,
        previewer: Previewer,
        has_glyph: Callable[[str], bool],
        clock: Callable[[], float],
    ) -> None:
        self.settings = settings
        self.link = link
        self.previewer = previewer
        self.has_glyph = has_glyph
        self.clock = clock
        rate = settings.rate_limit_per_minute
        self.submit_limiter = SlidingWindowLimiter(rate)
        self.address_limiter = SlidingWindowLimiter(rate * settings.clients_per_address)
        self.preview_limiter = SlidingWindowLimiter(settings.preview_rate_per_minute)

    def check_rate(self, client: Client, *, preview: bool) -> None:
        now = self.clock()
        if preview:
            wait = self.preview_limiter.hit(client.key, now)
        else:
            wait = self.submit_limiter.hit(client.key, now)
            if wait is None:
                wait = self.address_limiter.hit(client.address, now)
        if wait is not None:
            seconds = max(1, round(wait))
            raise RejectedError(
                "rate_limited",
                wording.RATE_LIMITED.format(seconds=seconds),
                status=429,
                retry_after_s=wait,
            )

    async def checked_body(self, request: Request) -> Submission:
        raw = await read_capped(request, self.settings.limits.max_payload_bytes)
        data = decode_json_body(raw)
        return check_submission(data, self.settings.limits, self.has_glyph)

    def job_for(self, request: Request) -> str:
        job_id = str(request.path_params["job_id"])
        token = request.query_params.get("token") or request.headers.get("x-job-token")
        if self.link.book.get(job_id) is None:
            raise RejectedError("unknown_job", wording.UNKNOWN_JOB, status=404)
        if self.link.book.authorised(job_id, token) is None:
            raise RejectedError("not_your_job", wording.NOT_YOUR_JOB, status=403)
        return job_id


def _ok(payload: dict[str, Any], client: Client | None = None, *, secure: bool = False) -> Response:
    response = JSONResponse({"ok": True, **payload})
    return remember(response, client, secure=secure) if client is not None else response


def _refusal(request: Request, exc: Exception) -> Response:
    if not isinstance(exc, RejectedError):  # pragma: no cover - typed by Starlette's registry
        raise exc
    headers = {}
    if exc.retry_after_s is not None:
        headers["Retry-After"] = str(max(1, round(exc.retry_after_s)))
    response = JSONResponse({"ok": False, "error": exc.to_json_dict()}, exc.status, headers=headers)
    client = getattr(request.state, "kiosk_client", None)
    kiosk: Kiosk = request.app.state.kiosk
    return remember(response, client, secure=kiosk.settings.secure_cookie) if client else response


def _crash(request: Request, exc: Exception) -> Response:
    log.exception("kiosk request %s failed", request.url.path, exc_info=exc)
    error = {"code": "internal", "message": "Something went wrong on our side. Please try again."}
    return JSONResponse({"ok": False, "error": error}, 500)


def _reply_rejection(reply: SubmitReply) -> RejectedError:
    code = reply.error.code if reply.error is not None else "refused"
    if code in ("queue_full", "paused", "unavailable"):
        return RejectedError(code, wording.QUEUE_FULL, status=503, retry_after_s=60.0)
    return RejectedError(code, wording.ORCHESTRATOR_REFUSED, status=422)


async def page(request: Request) -> Response:
    kiosk: Kiosk = request.app.state.kiosk
    response = FileResponse(STATIC_DIR / "index.html", headers={"Cache-Control": "no-cache"})
    return remember(response, identify(request), secure=kiosk.settings.secure_cookie)


async def config(request: Request) -> Response:
    s: Kiosk = request.app.state.kiosk
    lim = s.settings.limits
    return _ok({"config": {
        "show_id": s.settings.show_id,
        "max_text_chars": lim.max_text_chars,
        "max_strokes": lim.max_strokes,
        "max_points": lim.max_points,
        "max_payload_bytes": lim.max_payload_bytes,
        "writing_area_m": list(s.settings.writing_area_m),
    }})  # fmt: skip


async def preview(request: Request) -> Response:
    kiosk: Kiosk = request.app.state.kiosk
    client = identify(request)
    kiosk.check_rate(client, preview=True)
    submission = await kiosk.checked_body(request)
    result = await run_in_threadpool(kiosk.previewer, submission)
    return _ok({"preview": result}, client, secure=kiosk.settings.secure_cookie)


async def submit(request: Request) -> Response:
    kiosk: Kiosk = request.app.state.kiosk
    client = identify(request)
    kiosk.check_rate(client, preview=False)
    submission = await kiosk.checked_body(request)
    planned = await run_in_threadpool(kiosk.previewer, submission)
    bus_request = SubmitRequest(
        text=submission.text, strokes=submission.strokes, client_id=client.public_id
    )
    try:
        reply = await kiosk.link.submit(bus_request)
    except OrchestratorUnavailableError:
        raise RejectedError(
            "unavailable", wording.NO_ORCHESTRATOR, status=503, retry_after_s=30.0
        ) from None
    if not reply.ok or reply.job_id is None:
        raise _reply_rejection(reply)
    book = kiosk.link.book
    job = book.add(
        reply.job_id, session_id=client.session_id, label=submission.label, preview=planned
    )
    kiosk.link.apply(_initial_state(reply, submission, client))
    state = book.state(reply.job_id)
    payload = {
        "job_id": job.job_id,
        "token": job.token,
        "label": submission.label,
        "job": job_view(state) if state is not None else None,
        "preview": planned,
    }
    return _ok(payload, client, secure=kiosk.settings.secure_cookie)


def _initial_state(reply: SubmitReply, submission: Submission, client: Client) -> JobState:
    """What the submit reply says, stamped older than anything the orchestrator publishes."""
    assert reply.job_id is not None
    return JobState(
        job_id=reply.job_id,
        state=reply.state or "submitted",
        label=submission.label,
        kind="text" if submission.text is not None else "strokes",
        client_id=client.public_id,
        created_at_s=time.time(),
        updated_at_s=0.0,
        queue_position=reply.queue_position,
        eta_s=reply.eta_s,
    )


async def job_status(request: Request) -> Response:
    kiosk: Kiosk = request.app.state.kiosk
    job_id = kiosk.job_for(request)
    state = kiosk.link.book.state(job_id) or await kiosk.link.fetch(job_id)
    job = kiosk.link.book.get(job_id)
    return _ok({
        "job": job_view(state) if state is not None else None,
        "preview": job.preview if job is not None else None,
    })  # fmt: skip


async def job_stream(request: Request) -> Response:
    kiosk: Kiosk = request.app.state.kiosk
    job_id = kiosk.job_for(request)
    if kiosk.link.watcher_count >= MAX_STREAMS:
        raise RejectedError("busy", wording.NO_ORCHESTRATOR, status=503, retry_after_s=30.0)
    headers = {"Cache-Control": "no-store", "X-Accel-Buffering": "no"}
    return StreamingResponse(
        job_events(kiosk.link, job_id), media_type="text/event-stream", headers=headers
    )


async def health(request: Request) -> Response:
    kiosk: Kiosk = request.app.state.kiosk
    return _ok({"streams": kiosk.link.watcher_count})


def create_app(
    settings: KioskSettings,
    link: OrchestratorLink,
    previewer: Previewer,
    *,
    has_glyph: Callable[[str], bool],
    clock: Callable[[], float] = time.monotonic,
) -> Starlette:
    """The kiosk's ASGI application; its lifespan starts and stops ``link``."""

    @contextlib.asynccontextmanager
    async def lifespan(app: Starlette) -> AsyncIterator[None]:
        await link.start()
        try:
            yield
        finally:
            await link.close()

    routes = [
        Route("/", page),
        Route("/healthz", health),
        Route("/api/config", config),
        Route("/api/preview", preview, methods=["POST"]),
        Route("/api/submit", submit, methods=["POST"]),
        Route("/api/jobs/{job_id}", job_status),
        Route("/api/jobs/{job_id}/events", job_stream),
        Mount("/static", StaticFiles(directory=STATIC_DIR), name="static"),
    ]
    app = Starlette(
        routes=routes,
        middleware=[Middleware(SecurityHeaders)],
        exception_handlers={RejectedError: _refusal, Exception: _crash},
        lifespan=lifespan,
    )
    app.state.kiosk = Kiosk(settings, link, previewer, has_glyph, clock)
    return app

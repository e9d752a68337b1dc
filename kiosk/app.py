"""The kiosk web application: one page and a small JSON API (Starlette).

Routes
    GET  /                          the page
    GET  /api/config                limits the page needs (text length, strokes, points, area)
    POST /api/preview               ``{"text": ...}`` or ``{"strokes": {...}}`` -> planned path;
                                    ``{"text": ..., "phrase": true}``: a phrase, one character
                                    per board of the row, each planned (``kiosk/phrase_view.py``
                                    follows it as one ticket; it counts as its characters)
    POST /api/submit                same body -> ticket, token, job id, queue place, ETA, path
                                    (202 with a pending ticket when the queue did not answer yet)
    GET  /api/jobs/{id}?token=T     the ticket's state (id: ticket or job id; token from submit)
    GET  /api/jobs/{id}/events?token=T   server-sent events of the ticket until it is final
    GET  /api/jobs/{id}/qr.svg?token=T   QR code of the ticket's ``/t/<code>`` link
    GET  /t/{code}                  the page, following the ticket of a short code
    GET  /api/t/{code}              the ticket (id, token) a short code opens (rate limited)
    /crew, /crew/api/...            the crew's page, when the kiosk holds the crew's session
                                    (``kiosk/crew/routes.py``)

Every refusal is ``{"ok": false, "error": {"code": ..., "message": ...}}`` with a message for the
public; nothing a visitor sends can stop the service. The POST routes take ``application/json``
only (415) from the kiosk's own page (``Origin``, when sent, is the kiosk's: 403 otherwise);
headers are capped (431, :data:`kiosk.http.MAX_HEADER_BYTES`).
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

from bus.messages import JobState, PhrasePlace, SubmitReply, SubmitRequest
from bus.ratelimit import SlidingWindowLimiter
from kiosk import wording
from kiosk.addresses import proxy_networks
from kiosk.crew.routes import ROUTES as CREW_ROUTES
from kiosk.crew.routes import CrewDesk
from kiosk.errors import RejectedError
from kiosk.http import (
    Client,
    HeaderCap,
    SecurityHeaders,
    check_same_origin_json,
    identify,
    read_capped,
    remember,
)
from kiosk.jobs import KioskJob
from kiosk.limits import Submission, check_submission, decode_json_body
from kiosk.link import OrchestratorLink, OrchestratorUnavailableError
from kiosk.qr import qr_svg
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
        self.proxies = proxy_networks(settings.trusted_proxies)
        """Peers whose ``X-Forwarded-For`` is believed."""
        self.submit_limiter = SlidingWindowLimiter(settings.rate_limit_per_minute)
        self.preview_limiter = SlidingWindowLimiter(settings.preview_rate_per_minute)

    def identify(self, request: Request) -> Client:
        """Who sent ``request`` (see :func:`kiosk.http.identify`)."""
        return identify(request, self.proxies)

    def check_rate(self, client: Client, *, preview: bool, count: int = 1) -> None:
        """Count ``count`` requests of ``client``'s address (a phrase's characters beyond the
        first: it counts as its characters); RejectedError (429) over the limit."""
        limiter = self.preview_limiter if preview else self.submit_limiter
        now_s = self.clock()
        waits = [w for _ in range(count) if (w := limiter.hit(client.rate_key, now_s)) is not None]
        wait = max(waits, default=None)
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

    def job_for(self, request: Request) -> KioskJob:
        ref = str(request.path_params["job_id"])
        token = request.query_params.get("token") or request.headers.get("x-job-token")
        if self.link.book.get(ref) is None:
            raise RejectedError("unknown_job", wording.UNKNOWN_JOB, status=404)
        job = self.link.book.authorised(ref, token)
        if job is None:
            raise RejectedError("not_your_job", wording.NOT_YOUR_JOB, status=403)
        return job

    def on_late_reply(self, ticket: str, reply: SubmitReply, request: SubmitRequest) -> None:
        """The answer to a pending submission arrived (after a retry)."""
        book = self.link.book
        if reply.ok and reply.job_id is not None:
            job = book.bind(ticket, reply.job_id)
            if job is not None:
                self.link.apply(_initial_state(reply, job.label, request))
        else:
            rejection = _reply_rejection(reply)
            book.refuse(ticket, rejection.message, rejection.code)


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
    if code in ("queue_full", "paused", "unavailable", "storage_full"):
        return RejectedError(code, wording.QUEUE_FULL, status=503, retry_after_s=60.0)
    return RejectedError(code, wording.ORCHESTRATOR_REFUSED, status=422)


async def page(request: Request) -> Response:
    kiosk: Kiosk = request.app.state.kiosk
    response = FileResponse(STATIC_DIR / "index.html", headers={"Cache-Control": "no-cache"})
    return remember(response, kiosk.identify(request), secure=kiosk.settings.secure_cookie)


async def config(request: Request) -> Response:
    s: Kiosk = request.app.state.kiosk
    lim = s.settings.limits
    return _ok({"config": {
        "show_id": s.settings.show_id,
        "max_text_chars": lim.max_text_chars,
        "max_phrase_chars": lim.max_phrase_chars,
        "max_strokes": lim.max_strokes,
        "max_points": lim.max_points,
        "max_payload_bytes": lim.max_payload_bytes,
        "writing_area_m": list(s.settings.writing_area_m),
        "max_flight_s": s.settings.max_flight_s,
        "idle_reset_s": s.settings.idle_reset_s,
        "width_range_m": s.settings.width_range_m and list(s.settings.width_range_m),
    }})  # fmt: skip


async def preview(request: Request) -> Response:
    kiosk: Kiosk = request.app.state.kiosk
    check_same_origin_json(request)  # before the rate limit: another site spends no quota
    client = kiosk.identify(request)
    kiosk.check_rate(client, preview=True)
    submission = await kiosk.checked_body(request)
    if submission.characters > 1:  # each character of a phrase is planned
        kiosk.check_rate(client, preview=True, count=submission.characters - 1)
    result = await run_in_threadpool(kiosk.previewer, submission)
    return _ok({"preview": result}, client, secure=kiosk.settings.secure_cookie)


async def submit(request: Request) -> Response:
    kiosk: Kiosk = request.app.state.kiosk
    check_same_origin_json(request)
    client = kiosk.identify(request)
    kiosk.check_rate(client, preview=False)
    submission = await kiosk.checked_body(request)
    if submission.characters > 1:  # a phrase counts as its characters
        kiosk.check_rate(client, preview=False, count=submission.characters - 1)
    planned = await run_in_threadpool(kiosk.previewer, submission)
    book = kiosk.link.book
    if book.pending_count() >= kiosk.settings.max_pending:  # refused before anything is sent
        raise RejectedError("unavailable", wording.PENDING_FULL, status=503, retry_after_s=30.0)
    job = book.add(session_id=client.session_id, label=submission.label, preview=planned,
                   phrase_size=submission.characters if submission.phrase else 0)  # fmt: skip
    bus_request = SubmitRequest(
        text=submission.text,
        strokes=submission.strokes,
        client_id=client.public_id,
        idempotency_key=job.key,
        phrase=submission.phrase,
    )
    status = 200
    try:
        reply = await kiosk.link.submit(bus_request)
    except OrchestratorUnavailableError:
        # It may still be queued late: keep the ticket and ask again with the same key.
        kiosk.link.follow_up(
            job.ticket, bus_request, lambda t, r: kiosk.on_late_reply(t, r, bus_request)
        )
        status = 202
    else:
        if not reply.ok or reply.job_id is None:
            book.drop(job.ticket)
            raise _reply_rejection(reply)
        book.bind(job.ticket, reply.job_id)
        kiosk.link.apply(_initial_state(reply, submission.label, bus_request))
    payload = {
        "ticket": job.ticket,
        "code": job.code,
        "job_id": job.job_id,
        "token": job.token,
        "label": submission.label,
        "job": book.view(job, kiosk.settings.places),
        "preview": planned,
    }
    response = JSONResponse({"ok": True, **payload}, status)
    return remember(response, client, secure=kiosk.settings.secure_cookie)


def _initial_state(reply: SubmitReply, label: str, request: SubmitRequest) -> JobState:
    """What the submit reply says, stamped older than anything the orchestrator publishes (of a
    phrase: its first character, whose job id is the phrase's)."""
    assert reply.job_id is not None
    size = len(request.text or "")
    phrase = PhrasePlace(phrase_id=reply.job_id, index=0, size=size) if request.phrase else None
    return JobState(
        job_id=reply.job_id,
        state=reply.state or "submitted",
        kind="text" if request.text is not None else "strokes",
        client_id=request.client_id,
        created_at_s=time.time(),
        updated_at_s=0.0,
        queue_position=reply.queue_position,
        eta_s=reply.eta_s,
        label=label[:1] if phrase is not None else label,
        phrase=phrase,
    )


async def job_status(request: Request) -> Response:
    kiosk: Kiosk = request.app.state.kiosk
    job = kiosk.job_for(request)
    if kiosk.link.book.unknown(job):
        await kiosk.link.fetch(job.job_id or "")
    return _ok({
        "ticket": job.ticket,
        "code": job.code,
        "job": kiosk.link.book.view(job, kiosk.settings.places),
        "preview": job.preview,
        "stale": kiosk.link.stale(kiosk.settings.stale_after_s),
    })  # fmt: skip


async def job_stream(request: Request) -> Response:
    kiosk: Kiosk = request.app.state.kiosk
    job = kiosk.job_for(request)
    if kiosk.link.watcher_count >= MAX_STREAMS:
        raise RejectedError("busy", wording.NO_ORCHESTRATOR, status=503, retry_after_s=30.0)
    headers = {"Cache-Control": "no-store", "X-Accel-Buffering": "no"}
    events = job_events(
        kiosk.link,
        job.ticket,
        stale_after_s=kiosk.settings.stale_after_s,
        places=kiosk.settings.places,
    )
    return StreamingResponse(events, media_type="text/event-stream", headers=headers)


async def by_code(request: Request) -> Response:
    """What the page needs to follow the ticket of a short code typed or scanned elsewhere."""
    kiosk: Kiosk = request.app.state.kiosk
    kiosk.check_rate(kiosk.identify(request), preview=True)  # bounds guessing
    job = kiosk.link.book.by_code(str(request.path_params["code"]))
    if job is None:
        raise RejectedError("unknown_job", wording.UNKNOWN_CODE, status=404)
    return _ok({
        "ticket": job.ticket, "token": job.token, "code": job.code, "label": job.label,
        "preview": job.preview, "job": kiosk.link.book.view(job, kiosk.settings.places),
    })  # fmt: skip


async def ticket_qr(request: Request) -> Response:
    kiosk: Kiosk = request.app.state.kiosk
    job = kiosk.job_for(request)
    url = f"{str(request.base_url).rstrip('/')}/t/{job.code}"
    headers = {"Cache-Control": "private, max-age=3600"}
    return Response(qr_svg(url), media_type="image/svg+xml", headers=headers)


async def health(request: Request) -> Response:
    kiosk: Kiosk = request.app.state.kiosk
    stale = kiosk.link.stale(kiosk.settings.stale_after_s)
    return _ok({"streams": kiosk.link.watcher_count, "stale": stale})


def create_app(
    settings: KioskSettings,
    link: OrchestratorLink,
    previewer: Previewer,
    *,
    has_glyph: Callable[[str], bool],
    clock: Callable[[], float] = time.monotonic,
    crew: CrewDesk | None = None,
) -> Starlette:
    """The kiosk's ASGI application; its lifespan starts and stops ``link`` (and the crew's);
    ``crew``: the crew page's desk (None: no crew page)."""

    @contextlib.asynccontextmanager
    async def lifespan(app: Starlette) -> AsyncIterator[None]:
        await link.start()
        if crew is not None:
            await crew.link.start()
        try:
            yield
        finally:
            if crew is not None:
                await crew.link.close()
            await link.close()

    routes = [
        Route("/", page),
        Route("/healthz", health),
        Route("/api/config", config),
        Route("/api/preview", preview, methods=["POST"]),
        Route("/api/submit", submit, methods=["POST"]),
        Route("/api/jobs/{job_id}", job_status),
        Route("/api/jobs/{job_id}/events", job_stream),
        Route("/api/jobs/{job_id}/qr.svg", ticket_qr),
        Route("/t/{code}", page),
        Route("/api/t/{code}", by_code),
        *(CREW_ROUTES if crew is not None else ()),
        Mount("/static", StaticFiles(directory=STATIC_DIR), name="static"),
    ]
    app = Starlette(
        routes=routes,
        middleware=[Middleware(SecurityHeaders), Middleware(HeaderCap)],
        exception_handlers={RejectedError: _refusal, Exception: _crash},
        lifespan=lifespan,
    )
    app.state.kiosk = Kiosk(settings, link, previewer, has_glyph, clock)
    app.state.crew = crew
    return app


def end_streams(app: Starlette) -> None:
    """Close every open stream, the public's and the crew's (server shutdown)."""
    app.state.kiosk.link.end_streams()
    if app.state.crew is not None:
        app.state.crew.link.end_streams()

"""HTTP plumbing of the kiosk: client identity, capped body and headers, same-origin JSON,
security headers."""

from __future__ import annotations

import hashlib
import re
import secrets
from collections.abc import Sequence
from dataclasses import dataclass
from urllib.parse import urlsplit

from starlette.requests import Request
from starlette.responses import JSONResponse, Response
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from kiosk import wording
from kiosk.addresses import IPNetwork, client_address, rate_key
from kiosk.errors import RejectedError

SESSION_COOKIE = "skyquill_kiosk"
"""Name of the cookie that identifies one browser (no personal data)."""
_SESSION_RE = re.compile(r"^[A-Za-z0-9_-]{20,64}$")
MAX_HEADER_BYTES = 16 * 1024
"""Most bytes of a request's header names and values together; beyond, 431."""
_HEADERS = [
    (b"content-security-policy",
     b"default-src 'self'; img-src 'self' data:; object-src 'none'; frame-ancestors 'none'; "
     b"base-uri 'none'; form-action 'self'"),
    (b"x-content-type-options", b"nosniff"),
    (b"referrer-policy", b"no-referrer"),
    (b"x-frame-options", b"DENY"),
]  # fmt: skip


@dataclass(frozen=True)
class Client:
    """Who is asking: the client's address and the browser's session cookie."""

    address: str
    """Client IP address: the peer's, or the one a trusted proxy forwarded (see kiosk.addresses)."""
    session_id: str
    """Value of the session cookie (fresh when the browser had none)."""
    new_session: bool
    """True when the cookie must be set on the response."""

    @property
    def rate_key(self) -> str:
        """Rate-limit key: the address alone (cookies can be dropped); an IPv6 client's /64."""
        return rate_key(self.address)

    @property
    def public_id(self) -> str:
        """A stable pseudonym for the bus (the cookie itself stays secret)."""
        digest = hashlib.sha256(self.session_id.encode()).hexdigest()
        return f"kiosk-{digest[:12]}"


def identify(request: Request, proxies: Sequence[IPNetwork] = ()) -> Client:
    """The client of ``request``; a missing or malformed cookie gets a fresh session id.

    ``X-Forwarded-For`` counts only when the peer is one of ``proxies``. The answer is kept on
    ``request.state`` so refusals set the same new cookie.
    """
    known = getattr(request.state, "kiosk_client", None)
    if isinstance(known, Client):
        return known
    peer = request.client.host if request.client is not None else "unknown"
    address = client_address(peer, request.headers.getlist("x-forwarded-for"), proxies)
    cookie = request.cookies.get(SESSION_COOKIE, "")
    if _SESSION_RE.match(cookie):
        client = Client(address, cookie, False)
    else:
        client = Client(address, secrets.token_urlsafe(24), True)
    request.state.kiosk_client = client
    return client


def remember(response: Response, client: Client, *, secure: bool) -> Response:
    """Set the session cookie on ``response`` when the client is new."""
    if client.new_session:
        response.set_cookie(
            SESSION_COOKIE,
            client.session_id,
            max_age=7 * 24 * 3600,
            httponly=True,
            samesite="strict",
            secure=secure,
        )
    return response


async def read_capped(request: Request, max_bytes: int) -> bytes:
    """The request body, refusing (413) anything longer than ``max_bytes`` before reading it all."""
    declared = request.headers.get("content-length")
    if declared is not None:
        if not declared.isdigit():
            raise RejectedError("bad_request", wording.BAD_JSON)
        if int(declared) > max_bytes:
            raise RejectedError("too_large", wording.TOO_LARGE, status=413)
    chunks: list[bytes] = []
    size = 0
    async for chunk in request.stream():
        size += len(chunk)
        if size > max_bytes:
            raise RejectedError("too_large", wording.TOO_LARGE, status=413)
        chunks.append(chunk)
    return b"".join(chunks)


def check_same_origin_json(request: Request) -> None:
    """Refuse a body that is not ``application/json`` (415) or that a page of another origin
    sent (403: its ``Origin`` is not the kiosk's own, the host the visitor's browser asked for).

    A page elsewhere can make a visitor's browser post a form or ``text/plain`` without asking;
    a JSON body needs a CORS preflight, which the kiosk never grants.
    """
    media_type = request.headers.get("content-type", "").partition(";")[0].strip().lower()
    if media_type != "application/json":
        raise RejectedError("unsupported_media_type", wording.BAD_JSON, status=415)
    origin = request.headers.get("origin")
    if origin is None:
        return
    parts = urlsplit(origin)
    host = request.headers.get("host", "").lower()
    if parts.scheme not in ("http", "https") or not host or parts.netloc.lower() != host:
        raise RejectedError("cross_origin", wording.BAD_JSON, status=403)


class HeaderCap:
    """ASGI middleware: a request whose headers exceed :data:`MAX_HEADER_BYTES` in all is
    refused (431) before any route reads them."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] == "http":
            size = sum(len(name) + len(value) for name, value in scope["headers"])
            if size > MAX_HEADER_BYTES:
                error = RejectedError("headers_too_large", wording.BAD_JSON, status=431)
                reply = JSONResponse({"ok": False, "error": error.to_json_dict()}, error.status)
                await reply(scope, receive, send)
                return
        await self.app(scope, receive, send)


class SecurityHeaders:
    """ASGI middleware: a strict content security policy and no caching of API replies."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        is_api = str(scope.get("path", "")).startswith("/api/")

        async def send_with_headers(message: Message) -> None:
            if message["type"] == "http.response.start":
                headers = list(message.get("headers", []))
                headers.extend(_HEADERS)
                if is_api:
                    headers.append((b"cache-control", b"no-store"))
                message["headers"] = headers
            await send(message)

        await self.app(scope, receive, send_with_headers)

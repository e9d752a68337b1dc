"""The crew page's routes on the kiosk's server, apart from the public's.

Routes
    GET  /crew                  the page (phone-sized; Chinese and English)
    POST /crew/api/pair         ``{"code": ...}``: a code from ``skyquill crew SHOW --pair NAME``
                                pairs this phone (an HttpOnly cookie on ``/crew``; rate limited)
    GET  /crew/api/me           the paired phone's name (401 until paired)
    GET  /crew/api/events       server-sent events: ``tasks`` (boards waiting for a sheet,
                                vehicles waiting for a battery) on every change, ``live``
    POST /crew/api/confirm      ``{"command": "fresh_sheet" | "battery_swapped", "target": ID}``
                                -> the orchestrator's answer

Every crew route but the page and the pairing needs a paired phone's cookie; the confirmations
go out on the crew's session (:mod:`kiosk.crew.link`), which the public's routes never reach.
"""

from __future__ import annotations

import asyncio
import re
import time
from collections.abc import AsyncIterator, Callable, Mapping
from pathlib import Path
from typing import Any

from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, Response, StreamingResponse
from starlette.routing import Route

from bus.bridge import ChannelClosedError
from bus.ratelimit import SlidingWindowLimiter
from kiosk.crew.link import CrewLink
from kiosk.crew.pairing import PHONE_TTL_S, PairingFile, new_token
from kiosk.crew.tasks import COMMANDS
from kiosk.errors import RejectedError
from kiosk.http import check_same_origin_json, identify, read_capped
from kiosk.limits import decode_json_body
from kiosk.sse import BEAT_S, sse_event

PAGE = Path(__file__).resolve().parents[1] / "static" / "crew.html"
COOKIE = "skyquill_crew"
"""The paired phone's token (HttpOnly, SameSite=Strict, only sent to ``/crew``)."""
TRIES_PER_MINUTE = 5
"""Pairing tries per address per minute (a code has ~40 bits: guessing is hopeless)."""
MAX_BODY_BYTES = 1024
_ID = re.compile(r"^[A-Za-z0-9_.-]{1,64}$")
NO_STORE = {"Cache-Control": "no-store"}
# what a program reads in ``error.message``; the page words each ``error.code`` itself
NOT_PAIRED = "This phone is not paired: enter the code the operator gave you."
BAD_CODE = "That code is unknown, used or expired: ask the operator for a new one."
FORBIDDEN = "The crew page confirms fresh sheets and battery swaps only."
BAD_REQUEST = "Not a confirmation of the crew page."
RATE_LIMITED = "Too many tries: wait {seconds} s."


class CrewDesk:
    """The state behind the crew's routes: its link, the paired phones, the pairing limiter."""

    def __init__(
        self,
        link: CrewLink,
        phones: PairingFile,
        *,
        secure_cookie: bool = False,
        stale_after_s: float = 2.0,
        clock: Callable[[], float] = time.monotonic,
        wall_clock: Callable[[], float] = time.time,
    ) -> None:
        self.link = link
        self.phones = phones
        self.secure_cookie = secure_cookie
        self.stale_after_s = stale_after_s
        self.clock = clock
        self.wall_clock = wall_clock
        """Unix time: codes and pairings are kept in a file the CLI writes too."""
        self.tries = SlidingWindowLimiter(TRIES_PER_MINUTE)

    def phone(self, request: Request) -> str:
        """The paired phone's name; 401 for any other request."""
        token = request.cookies.get(COOKIE, "")
        name = self.phones.read().holder(token, self.wall_clock()) if token else None
        if name is None:
            raise RejectedError("not_paired", NOT_PAIRED, status=401)
        return name


def _desk(request: Request) -> CrewDesk:
    desk: CrewDesk = request.app.state.crew
    return desk


async def _body(request: Request) -> Mapping[str, Any]:
    check_same_origin_json(request)
    return decode_json_body(await read_capped(request, MAX_BODY_BYTES))


async def page(_request: Request) -> Response:
    return FileResponse(PAGE, headers={"Cache-Control": "no-cache"})


async def pair(request: Request) -> Response:
    desk = _desk(request)
    data = await _body(request)
    wait = desk.tries.hit(identify(request).rate_key, desk.clock())
    if wait is not None:
        message = RATE_LIMITED.format(seconds=max(1, round(wait)))
        raise RejectedError("rate_limited", message, status=429, retry_after_s=wait)
    code, token, now_s = data.get("code"), new_token(), desk.wall_clock()
    if not isinstance(code, str) or len(code) > 32:
        raise RejectedError("bad_code", BAD_CODE, status=403)
    name = desk.phones.change(lambda book: book.paired(code, token, now_s))
    if name is None:
        raise RejectedError("bad_code", BAD_CODE, status=403)
    response = JSONResponse({"ok": True, "name": name}, headers=NO_STORE)
    response.set_cookie(COOKIE, token, max_age=int(PHONE_TTL_S), path="/crew", httponly=True,
                        samesite="strict", secure=desk.secure_cookie)  # fmt: skip
    return response


async def me(request: Request) -> Response:
    return JSONResponse({"ok": True, "name": _desk(request).phone(request)}, headers=NO_STORE)


async def _frames(desk: CrewDesk) -> AsyncIterator[str]:
    with desk.link.watch() as channel:
        while True:
            yield sse_event("tasks", {"tasks": desk.link.view()})
            while True:
                yield sse_event("live", {"stale": desk.link.stale(desk.stale_after_s)})
                try:
                    await asyncio.wait_for(channel.get(), timeout=BEAT_S)
                    break
                except TimeoutError:
                    continue
                except ChannelClosedError:  # the server is stopping
                    return


async def events(request: Request) -> Response:
    desk = _desk(request)
    desk.phone(request)
    headers = {**NO_STORE, "X-Accel-Buffering": "no"}
    return StreamingResponse(_frames(desk), media_type="text/event-stream", headers=headers)


async def confirm(request: Request) -> Response:
    desk = _desk(request)
    data = await _body(request)
    phone = desk.phone(request)
    command = next((c for c in COMMANDS if c == data.get("command")), None)
    target = data.get("target")
    if command is None:
        raise RejectedError("forbidden", FORBIDDEN, status=403)
    if not isinstance(target, str) or not _ID.match(target):
        raise RejectedError("bad_request", BAD_REQUEST)
    reply = await desk.link.confirm(command, target, phone)
    if reply.ok:
        return JSONResponse({"ok": True, "message": reply.message}, headers=NO_STORE)
    code = reply.error.code if reply.error is not None else "refused"
    error = {"code": code, "message": reply.message}
    return JSONResponse({"ok": False, "error": error}, 409, headers=NO_STORE)


ROUTES = [
    Route("/crew", page),
    Route("/crew/api/pair", pair, methods=["POST"]),
    Route("/crew/api/me", me),
    Route("/crew/api/events", events),
    Route("/crew/api/confirm", confirm, methods=["POST"]),
]

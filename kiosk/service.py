"""Run the kiosk: a Zenoh client session, the web app, and uvicorn serving it.

``run_kiosk(show)`` blocks until Ctrl-C (the ``skyquill kiosk`` command); :class:`KioskServer`
can also serve from a background thread (tests, embedding).
"""

from __future__ import annotations

import contextlib
import socket
import threading
from collections.abc import Callable, Iterator
from typing import Any

import uvicorn
from starlette.applications import Starlette

from bus.keys import ShowKeys
from bus.session import Role, Session, ZenohSettings, open_session
from kiosk.app import create_app, end_streams
from kiosk.crew.link import CrewLink
from kiosk.crew.pairing import PairingFile
from kiosk.crew.routes import CrewDesk
from kiosk.jobs import JobBook
from kiosk.link import OrchestratorLink
from kiosk.preview import make_previewer
from kiosk.settings import KioskSettings
from planner.glyphs import has_glyph


def build_app(
    settings: KioskSettings, session: Session, crew_session: Session | None = None
) -> Starlette:
    """The kiosk application on an open bus session (the sessions outlive the app); with the
    crew's session (its own certificate) and ``settings.crew_phones``, the crew page too."""
    keys = ShowKeys(settings.show_id)
    link = OrchestratorLink(session, keys, JobBook(), timeout_s=settings.submit_timeout_s)
    crew = None
    if crew_session is not None and settings.crew_phones is not None:
        crew_link = CrewLink(
            crew_session, keys, settings.places, timeout_s=settings.submit_timeout_s
        )
        crew = CrewDesk(crew_link, PairingFile(settings.crew_phones),
                        secure_cookie=settings.secure_cookie,
                        stale_after_s=settings.stale_after_s)  # fmt: skip
    return create_app(settings, link, make_previewer(settings), has_glyph=has_glyph, crew=crew)


def page_url(host: str, port: int) -> str:
    """The URL people open; a wildcard host is shown as the loopback address."""
    shown = "127.0.0.1" if host in ("0.0.0.0", "", "::") else host
    if ":" in shown:
        shown = f"[{shown}]"
    return f"http://{shown}:{port}/"


class _Server(uvicorn.Server):
    def __init__(
        self,
        config: uvicorn.Config,
        on_started: Callable[[], None],
        before_shutdown: Callable[[], None],
    ) -> None:
        super().__init__(config)
        self._on_started = on_started
        self._before_shutdown = before_shutdown

    async def startup(self, sockets: list[socket.socket] | None = None) -> None:
        await super().startup(sockets=sockets)
        if self.started:
            self._on_started()

    async def shutdown(self, sockets: list[socket.socket] | None = None) -> None:
        self._before_shutdown()  # end the status streams, else connections never close
        await super().shutdown(sockets=sockets)


class KioskServer:
    """The kiosk's web server bound to a socket; ``url`` is known before it starts serving."""

    def __init__(
        self,
        app: Starlette,
        host: str,
        port: int,
        *,
        on_started: Callable[[str], None] | None = None,
        log_level: str = "warning",
    ) -> None:
        family = socket.AF_INET6 if ":" in host else socket.AF_INET
        self._socket = socket.socket(family, socket.SOCK_STREAM)
        self._socket.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self._socket.bind((host, port))
        self.port: int = self._socket.getsockname()[1]
        """The TCP port actually bound (useful with port 0)."""
        self.url = page_url(host, self.port)
        """The page's address."""
        self.ready = threading.Event()
        """Set once uvicorn accepts connections."""
        # proxy_headers off: the kiosk alone decides whose X-Forwarded-For to believe
        # (kiosk.addresses); uvicorn's default believes any loopback peer.
        config = uvicorn.Config(
            app, log_level=log_level, lifespan="on", access_log=False,
            timeout_graceful_shutdown=2, proxy_headers=False,
        )  # fmt: skip
        self._server = _Server(config, self._started, lambda: end_streams(app))
        self._on_started = on_started
        self._thread: threading.Thread | None = None

    def _started(self) -> None:
        self.ready.set()
        if self._on_started is not None:
            self._on_started(self.url)

    def run(self) -> None:
        """Serve until Ctrl-C or :meth:`stop` (blocking)."""
        try:
            self._server.run(sockets=[self._socket])
        finally:
            self._socket.close()

    def start_in_thread(self, timeout_s: float = 10.0) -> None:
        """Serve from a daemon thread; returns once serving (RuntimeError if it failed)."""
        self._thread = threading.Thread(target=self.run, name="kiosk-http", daemon=True)
        self._thread.start()
        if not self.ready.wait(timeout_s):
            self.stop()
            raise RuntimeError("the kiosk web server did not start")

    def stop(self, timeout_s: float = 10.0) -> None:
        """Ask the server to finish and wait for its thread."""
        self._server.should_exit = True
        if self._thread is not None:
            self._thread.join(timeout_s)


@contextlib.contextmanager
def _sessions(
    zenoh: ZenohSettings,
    crew_zenoh: ZenohSettings | None,
    role: Role,
    connect: list[str] | None = None,
) -> Iterator[tuple[Session, Session | None]]:
    """The public's session, and the crew's when its settings are given (a peer that does not
    listen: the public's session holds any ``peer_listen`` endpoint)."""
    with contextlib.ExitStack() as stack:
        session = stack.enter_context(open_session(zenoh, role=role, connect=connect))
        crew = None
        if crew_zenoh is not None:
            crew_session = open_session(crew_zenoh, role=role, listen=(), connect=connect)
            crew = stack.enter_context(crew_session)
        yield session, crew


@contextlib.contextmanager
def serving(
    settings: KioskSettings,
    zenoh: ZenohSettings,
    *,
    role: Role = "peer",
    crew_zenoh: ZenohSettings | None = None,
    **server_options: Any,
) -> Iterator[KioskServer]:
    """A kiosk serving from a background thread for the ``with`` block (tests, embedding);
    ``crew_zenoh``: the crew's session settings (its certificate), for the crew page."""
    with _sessions(zenoh, crew_zenoh, role) as (session, crew_session):
        server = KioskServer(build_app(settings, session, crew_session), settings.host,
                             settings.port, **server_options)  # fmt: skip
        server.start_in_thread()
        try:
            yield server
        finally:
            server.stop()


def run_kiosk(
    settings: KioskSettings,
    zenoh: ZenohSettings,
    *,
    role: Role = "peer",
    connect: list[str] | None = None,
    on_started: Callable[[str], None] = print,
    crew_zenoh: ZenohSettings | None = None,
) -> None:
    """Serve the kiosk until Ctrl-C; ``on_started(url)`` once the page can be opened;
    ``crew_zenoh``: the crew's session settings (its certificate), for the crew page.

    A ``peer`` session (default) starts even before the show's router is up and joins it when
    it appears; submissions made meanwhile get the "queue not answering" message.
    """
    with _sessions(zenoh, crew_zenoh, role, connect) as (session, crew_session):
        app = build_app(settings, session, crew_session)
        KioskServer(app, settings.host, settings.port, on_started=on_started).run()

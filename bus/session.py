"""The one place that opens Zenoh sessions.

Every process of a show opens its session with :func:`open_session` from the show's ``zenoh``
settings: explicit listen/connect endpoints, multicast scouting off unless the show turns it on,
TLS and access control passed through verbatim. Always use the result as a context manager::

    with open_session(show.zenoh, role="client") as session:
        ...

An unclosed session with callbacks can hang interpreter exit.
"""

from __future__ import annotations

import json
import socket
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, Protocol

import zenoh

Role = Literal["router", "peer", "client"]
"""How a process joins the show: ``router`` (the hub, usually inside ``skyquill up``),
``peer`` (joins through the router, may link directly to other peers), ``client`` (one link)."""

Session = zenoh.Session
"""Re-exported so that services can annotate sessions without importing zenoh."""


class BusError(Exception):
    """Root of the errors raised by :mod:`bus` helpers (other than message decoding)."""


class SessionOpenError(BusError):
    """No session could be opened (no router reachable, bad endpoint, bad TLS files...)."""


class ZenohSettings(Protocol):
    """What :func:`open_session` reads; ``showfile.ZenohSettings`` satisfies it structurally."""

    @property
    def router_listen(self) -> Sequence[str]:
        """Endpoints the router listens on, e.g. ``tcp/127.0.0.1:7447``."""
        ...

    @property
    def connect(self) -> Sequence[str]:
        """Endpoints clients and peers connect to (the router's, as seen from them)."""
        ...

    @property
    def multicast_scouting(self) -> bool:
        """Whether to discover others by UDP multicast (off by default: explicit endpoints)."""
        ...


@dataclass(frozen=True)
class BusSettings:
    """A plain :class:`ZenohSettings` for tests and tools that have no show file."""

    router_listen: Sequence[str]
    """Endpoints the router listens on."""
    connect: Sequence[str]
    """Endpoints clients and peers connect to."""
    multicast_scouting: bool = False
    """Discover by UDP multicast."""
    router_connect: Sequence[str] = ()
    """Other routers this router links to (multi-host venues)."""
    peer_listen: Sequence[str] = ()
    """Endpoints a peer listens on (none: peers reach each other through the router)."""
    tls: Mapping[str, Any] | None = None
    """Verbatim ``transport/link/tls`` section of the Zenoh configuration."""
    access_control: Mapping[str, Any] | None = None
    """Verbatim ``access_control`` section of the Zenoh configuration."""
    extra: Mapping[str, Any] = field(default_factory=dict)
    """Further Zenoh configuration: ``{"path/in/config": value}`` inserted as JSON5."""
    open_timeout_s: float = 5.0
    """How long a client or peer keeps retrying to reach a router before giving up, in [s]."""


def _opt(settings: object, name: str, default: Any) -> Any:
    value = getattr(settings, name, default)
    return default if value is None else value


def build_config(
    settings: ZenohSettings,
    *,
    role: Role,
    listen: Sequence[str] | None = None,
    connect: Sequence[str] | None = None,
) -> zenoh.Config:
    """The Zenoh configuration of a session with ``role`` (pure: builds, does not open).

    ``listen``/``connect`` override the endpoints from ``settings``. Optional attributes
    (``router_connect``, ``peer_listen``, ``tls``, ``access_control``, ``extra``) are read when the
    settings object has them, so any object with the three protocol attributes works.
    """
    if role not in ("router", "peer", "client"):
        raise ValueError(f"role must be router, peer or client, not {role!r}")
    if listen is None:
        if role == "router":
            listen = list(settings.router_listen)
        elif role == "peer":
            listen = list(_opt(settings, "peer_listen", ()))
        else:
            listen = []
    if connect is None:
        connect = (
            list(_opt(settings, "router_connect", ())) if role == "router" else settings.connect
        )
    if role == "client" and not connect:
        raise ValueError("a client needs at least one connect endpoint")
    conf = zenoh.Config()
    conf.insert_json5("mode", json.dumps(role))
    conf.insert_json5("listen/endpoints", json.dumps(list(listen)))
    conf.insert_json5("connect/endpoints", json.dumps(list(connect)))
    conf.insert_json5("scouting/multicast/enabled", json.dumps(bool(settings.multicast_scouting)))
    tls = _opt(settings, "tls", None)
    if tls:
        conf.insert_json5("transport/link/tls", json.dumps(dict(tls)))
    acl = _opt(settings, "access_control", None)
    if acl:
        conf.insert_json5("access_control", json.dumps(dict(acl)))
    _insert_resilience(conf)
    _insert_size_bounds(conf)
    for path, value in dict(_opt(settings, "extra", {})).items():
        conf.insert_json5(path, json.dumps(value))
    return conf


# --- resilience (same on the router and every client, so both sides agree) ---------------------

LINK_LEASE_MS = 2000
"""Zenoh link lease of every show session, [ms] (Zenoh's default: 10 s). A process silent this
long (frozen, cut off) is dropped by the other side of its link, and its liveliness tokens with
it; SIGKILL or a closed socket is noticed at once. ``extra`` may override it."""
LINK_KEEP_ALIVES = 4
"""Keep-alive messages per lease on an idle link (one every 500 ms)."""
RECONNECT_RETRY = {"period_init_ms": 100, "period_max_ms": 250, "period_increase_factor": 1.5}
"""How clients and peers retry a lost router: after 0.1 s, then every 0.15 s and 0.25 s, so a
router restarted by the supervisor is reached again at most 0.25 s after it listens, well
within ``policy.lost_after_s`` (1 s before). Measured, 3 vehicles: every vehicle heard again
0.42-0.65 s after the new router process started (0.61-0.63 s with the old retry: the router
listened early enough for both). Zenoh replays the session's subscribers, queryables and
liveliness tokens on the new link."""


def _insert_resilience(conf: zenoh.Config) -> None:
    conf.insert_json5("transport/link/tx/lease", json.dumps(LINK_LEASE_MS))
    conf.insert_json5("transport/link/tx/keep_alive", json.dumps(LINK_KEEP_ALIVES))
    conf.insert_json5("connect/retry", json.dumps(RECONNECT_RETRY))


# --- size bounds (every process, so the router drops what nobody would accept) -----------------

MAX_MESSAGE_BYTES = 2 * 1024 * 1024
"""Largest Zenoh message a session of the show takes in (``transport/link/rx/max_message_size``;
Zenoh's default: 1 GiB), [bytes]: twice the largest payload the bus accepts
(``bus.codec.MAX_PAYLOAD_BYTES``), so a request too large for its queryable up to this size still
gets its ``too_large`` reply. A larger message is dropped by the first process it reaches, the
router, before anyone else holds it; its querier hears no reply."""


def _insert_size_bounds(conf: zenoh.Config) -> None:
    """The message size bound, and Zenoh's shared memory off: with it on, a payload over 3 kB
    from a process on the same host travels as a reference into the sender's 16 MiB pool, which
    the router and the receiver map, so the bound above does not apply (a 5 MB query reached its
    queryable), and under a flood of large submissions the pools added 17-35 MiB to the
    resident set of the router and of the orchestrator (``benchmarks/bench_bus_memory.py``).
    The bus's messages are small (a request at most 256 KiB); copying them costs less."""
    conf.insert_json5("transport/link/rx/max_message_size", json.dumps(MAX_MESSAGE_BYTES))
    conf.insert_json5("transport/shared_memory/enabled", json.dumps(False))


def open_session(
    settings: ZenohSettings,
    *,
    role: Role,
    listen: Sequence[str] | None = None,
    connect: Sequence[str] | None = None,
    open_timeout_s: float | None = None,
) -> zenoh.Session:
    """Open a Zenoh session for ``role``; use the result in a ``with`` block.

    Clients and peers retry for ``open_timeout_s`` (default: the settings' ``open_timeout_s`` or
    5 s) while no router answers, so processes may start in any order. Raises
    :class:`SessionOpenError` when the deadline passes or the configuration is refused.
    """
    timeout_s = float(
        open_timeout_s if open_timeout_s is not None else _opt(settings, "open_timeout_s", 5.0)
    )
    deadline = time.monotonic() + max(0.0, timeout_s)
    delay_s = 0.05
    while True:
        try:
            conf = build_config(settings, role=role, listen=listen, connect=connect)
        except zenoh.ZError as exc:
            raise SessionOpenError(f"invalid Zenoh configuration: {exc}") from exc
        try:
            return zenoh.open(conf)
        except zenoh.ZError as exc:
            if role == "router" or time.monotonic() + delay_s > deadline:
                raise SessionOpenError(f"cannot open a Zenoh {role} session: {exc}") from exc
        time.sleep(delay_s)
        delay_s = min(0.5, delay_s * 2.0)


def free_tcp_endpoint(host: str = "127.0.0.1") -> str:
    """A ``tcp/HOST:PORT`` endpoint on a port free right now (for tests and temporary shows)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind((host, 0))
        port = sock.getsockname()[1]
    return f"tcp/{host}:{port}"


def loopback_settings(**overrides: Any) -> BusSettings:
    """Settings for one router on a free loopback port, clients connecting to it."""
    endpoint = free_tcp_endpoint()
    return BusSettings(router_listen=[endpoint], connect=[endpoint], **overrides)

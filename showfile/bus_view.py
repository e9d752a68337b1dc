"""The part of a show file that joining its bus takes (show id, vehicle ids, ``zenoh``,
``security``, and ``storage.database``, beside which the keys are by default), read without the
show-file models: pydantic and the models' schemas cost a one-off ``skyquill status`` about
0.35 s, more than everything else it does (benchmarks/bench_cli.py). Its paths are resolved as
the models' are (``showfile/paths.py``).

:func:`read_bus_view` checks these strictly (exact types, nothing coerced; of ``vehicles``, the
ids) and ignores the rest. It returns None for any file it does not vouch for (unreadable, not
YAML, a duplicate key, a value of another type, a field it does not know): load that one with
:func:`showfile.load_show`, whose errors name file, line and field. The defaults are those of
``showfile/services.py`` and ``showfile/security.py``; tests/test_showfile_bus_view.py keeps the two
equal on every show in ``shows/`` and fails when a model gains a field this view does not know.

:class:`ShowBus` is what :mod:`trust` reads of a show to open a session; both a loaded
:class:`showfile.Show` and a :class:`ShowBusView` are one.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, Protocol

import yaml

from showfile import paths
from showfile.roles import RESERVED_IDS

ID_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]*")
"""Show, vehicle and host ids (the models' ``ID_PATTERN``)."""
DEFAULT_ENDPOINTS = ("tcp/127.0.0.1:7447",)
"""The router's endpoint when the show names none."""


class HostBus(Protocol):
    """One host of a show across machines, as :mod:`trust.hosts` reads it."""

    @property
    def router_listen(self) -> tuple[str, ...]: ...
    @property
    def connect(self) -> tuple[str, ...]: ...
    @property
    def router_connect(self) -> tuple[str, ...]: ...
    @property
    def services(self) -> bool: ...
    @property
    def vehicles(self) -> tuple[str, ...]: ...
    @property
    def local_connect(self) -> tuple[str, ...]: ...


class ZenohBus(Protocol):
    """A show's ``zenoh`` section, as :mod:`trust` reads it."""

    @property
    def router_listen(self) -> tuple[str, ...]: ...
    @property
    def connect(self) -> tuple[str, ...]: ...
    @property
    def multicast_scouting(self) -> bool: ...
    @property
    def router_connect(self) -> tuple[str, ...]: ...
    @property
    def peer_listen(self) -> tuple[str, ...]: ...
    @property
    def extra(self) -> Mapping[str, Any]: ...
    @property
    def open_timeout_s(self) -> float: ...
    @property
    def hosts(self) -> Mapping[str, HostBus]: ...


class SecurityBus(Protocol):
    """A show's ``security`` section, as :mod:`trust` reads it."""

    @property
    def mode(self) -> Literal["mtls", "none"]: ...


class VehicleId(Protocol):
    """A vehicle of the show, as far as its identity goes."""

    @property
    def id(self) -> str: ...


class ShowBus(Protocol):
    """What opening a session of a show reads (:func:`trust.settings.session_settings`)."""

    @property
    def show_id(self) -> str: ...
    @property
    def vehicles(self) -> Sequence[VehicleId]: ...
    @property
    def zenoh(self) -> ZenohBus: ...
    @property
    def security(self) -> SecurityBus: ...
    @property
    def source_path(self) -> Path | None: ...
    @property
    def keys_dir(self) -> Path: ...


@dataclass(frozen=True)
class HostView:
    """``zenoh.hosts.<name>`` (see ``showfile.services.ZenohHost``)."""

    router_listen: tuple[str, ...]
    connect: tuple[str, ...] = ()
    router_connect: tuple[str, ...] = ()
    services: bool = False
    vehicles: tuple[str, ...] = ()

    @property
    def local_connect(self) -> tuple[str, ...]:
        """Where this host's processes reach its router."""
        return self.connect or self.router_listen[:1]


@dataclass(frozen=True)
class ZenohView:
    """``zenoh`` (see ``showfile.services.ZenohSettings``)."""

    router_listen: tuple[str, ...] = DEFAULT_ENDPOINTS
    connect: tuple[str, ...] = DEFAULT_ENDPOINTS
    multicast_scouting: bool = False
    router_connect: tuple[str, ...] = ()
    peer_listen: tuple[str, ...] = ()
    extra: Mapping[str, Any] = field(default_factory=dict)
    open_timeout_s: float = 5.0
    hosts: Mapping[str, HostView] = field(default_factory=dict)


@dataclass(frozen=True)
class SecurityView:
    """``security`` (see ``showfile.security.SecuritySettings``)."""

    mode: Literal["mtls", "none"] = "mtls"
    keys_dir: Path | None = None


@dataclass(frozen=True)
class VehicleView:
    """One entry of ``vehicles``: its id only."""

    id: str


@dataclass(frozen=True)
class ShowBusView:
    """The bus part of a show file (a :class:`ShowBus`)."""

    show_id: str
    vehicles: tuple[VehicleView, ...]
    zenoh: ZenohView
    security: SecurityView
    database: Path | None = None
    """``storage.database`` as written (the keys' default folder is beside it)."""
    source_path: Path | None = None
    """The file it was read from; its folder is where relative paths start."""

    @property
    def keys_dir(self) -> Path:
        """The show's CA, certificates and keys (``Show.keys_dir``: ``showfile.paths.keys_dir``)."""
        return paths.keys_dir(self.source_path, self.show_id, self.security.keys_dir, self.database)


class _NotVouchedError(Exception):
    """Something :func:`read_bus_view` leaves to the full loader."""


def read_bus_view(path: str | Path) -> ShowBusView | None:
    """The bus part of the show file at ``path``, or None when the full loader must judge it."""
    try:
        text = Path(path).read_text(encoding="utf-8")
        doc = _mapping(_compose(text), ())
        if "source_path" in doc:
            raise _NotVouchedError("source_path")
        return ShowBusView(
            show_id=_identifier(doc.get("show_id")),
            vehicles=_vehicles(doc.get("vehicles")),
            zenoh=_zenoh(_mapping(doc.get("zenoh", {}), _ZENOH_FIELDS)),
            security=_security(_mapping(doc.get("security", {}), _SECURITY_FIELDS)),
            database=_database(_mapping(doc.get("storage", {}), ())),
            source_path=Path(path),
        )
    except (OSError, UnicodeDecodeError, RecursionError, yaml.YAMLError, _NotVouchedError):
        return None


_ZENOH_FIELDS = (
    "router_listen",
    "connect",
    "multicast_scouting",
    "router_connect",
    "peer_listen",
    "extra",
    "open_timeout_s",
    "hosts",
)
_HOST_FIELDS = ("router_listen", "connect", "router_connect", "services", "vehicles")
_SECURITY_FIELDS = ("mode", "keys_dir")


def _compose(text: str) -> Any:
    """The YAML document; not vouched for when empty or when a mapping repeats a key (the loader
    refuses those)."""
    loader_class = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    loader = loader_class(text)
    try:
        node = loader.get_single_node()
        if node is None or _repeats_a_key(node):
            raise _NotVouchedError("empty or duplicate key")
        return loader.construct_document(node)
    finally:
        loader.dispose()


def _repeats_a_key(node: yaml.Node) -> bool:
    if isinstance(node, yaml.MappingNode):
        keys = [str(key.value) for key, _ in node.value]
        return len(set(keys)) < len(keys) or any(_repeats_a_key(v) for _, v in node.value)
    if isinstance(node, yaml.SequenceNode):
        return any(_repeats_a_key(item) for item in node.value)
    return False


def _mapping(value: Any, known: tuple[str, ...]) -> dict[str, Any]:
    """``value`` as a mapping with string keys, only ``known`` ones when ``known`` is given."""
    if not isinstance(value, dict) or not all(isinstance(k, str) for k in value):
        raise _NotVouchedError("not a mapping")
    if known and not set(value) <= set(known):
        raise _NotVouchedError("unknown field")
    return value


def _identifier(value: Any) -> str:
    if not isinstance(value, str) or not ID_PATTERN.fullmatch(value):
        raise _NotVouchedError("not an identifier")
    return value


def _vehicles(value: Any) -> tuple[VehicleView, ...]:
    """The vehicles' ids: at least one, distinct, none a role's name (the models' rules)."""
    if not isinstance(value, list) or not value:
        raise _NotVouchedError("vehicles")
    ids = [_identifier(_mapping(vehicle, ()).get("id")) for vehicle in value]
    if len(set(ids)) < len(ids) or RESERVED_IDS & set(ids):
        raise _NotVouchedError("vehicle ids")
    return tuple(VehicleView(vehicle_id) for vehicle_id in ids)


def _strings(value: Any) -> tuple[str, ...]:
    if not isinstance(value, list) or not all(isinstance(item, str) for item in value):
        raise _NotVouchedError("not a list of strings")
    return tuple(value)


def _exact(value: Any, kind: type) -> Any:
    if type(value) is not kind:  # bool is an int: compared exactly
        raise _NotVouchedError(f"not a {kind.__name__}")
    return value


def _zenoh(section: dict[str, Any]) -> ZenohView:
    defaults = ZenohView()
    timeout = section.get("open_timeout_s", defaults.open_timeout_s)
    if type(timeout) not in (int, float) or not timeout >= 0.0:
        raise _NotVouchedError("open_timeout_s")
    hosts = {
        _identifier(name): _host(_mapping(host, _HOST_FIELDS))
        for name, host in _mapping(section.get("hosts", {}), ()).items()
    }
    _check_hosts(hosts)
    view = ZenohView(
        router_listen=_strings(section.get("router_listen", list(defaults.router_listen))),
        connect=_strings(section.get("connect", list(defaults.connect))),
        multicast_scouting=_exact(section.get("multicast_scouting", False), bool),
        router_connect=_strings(section.get("router_connect", [])),
        peer_listen=_strings(section.get("peer_listen", [])),
        extra=dict(_mapping(section.get("extra", {}), ())),
        open_timeout_s=float(timeout),
        hosts=hosts,
    )
    if not view.multicast_scouting and not view.connect:
        raise _NotVouchedError("no connect endpoint")  # a cross-check of showfile/checks.py
    return view


def _host(section: dict[str, Any]) -> HostView:
    listen = _strings(section.get("router_listen"))
    if not listen:
        raise _NotVouchedError("router_listen")
    return HostView(
        router_listen=listen,
        connect=_strings(section.get("connect", [])),
        router_connect=_strings(section.get("router_connect", [])),
        services=_exact(section.get("services", False), bool),
        vehicles=tuple(_identifier(v) for v in _strings(section.get("vehicles", []))),
    )


def _check_hosts(hosts: Mapping[str, HostView]) -> None:
    """The models' rules for ``zenoh.hosts`` (their errors are the loader's to report)."""
    if not hosts:
        return
    if sum(host.services for host in hosts.values()) != 1:
        raise _NotVouchedError("not one ground station")
    if any(not host.services and not host.router_connect for host in hosts.values()):
        raise _NotVouchedError("a companion host without router_connect")
    placed = [v for host in hosts.values() for v in host.vehicles]
    if len(set(placed)) < len(placed):
        raise _NotVouchedError("a vehicle on two hosts")


def _security(section: dict[str, Any]) -> SecurityView:
    mode = section.get("mode", "mtls")
    keys_dir = section.get("keys_dir")
    if mode not in ("mtls", "none") or not (keys_dir is None or isinstance(keys_dir, str)):
        raise _NotVouchedError("security")
    return SecurityView(mode=mode, keys_dir=Path(keys_dir) if keys_dir is not None else None)


def _database(storage: dict[str, Any]) -> Path | None:
    """``storage.database`` (a string, as the models take it); the other fields of ``storage``
    are the loader's alone."""
    database = storage.get("database")
    if not (database is None or isinstance(database, str)):
        raise _NotVouchedError("storage.database")
    return Path(database) if database is not None else None

"""A show across several machines (``zenoh.hosts`` in the show file): which host each identity
runs on, and the endpoints its session uses there (pure).

One host is the ground station (``services: true``): its router is the show's hub, with the
identity ``router``; the orchestrator, the kiosk and every operator or outside client join it
there. Each companion host runs its own router, linked to the ground router, and the agents of
its vehicles, which reach only their local router. A companion router proves itself to the
ground router with a certificate of the show CA whose common name is ``router@<host>`` ('@' is
never part of a vehicle id), and the ground router's access control lets that identity send only
what the vehicles of that host may send: a companion computer that is taken over can speak for
its own vehicles and no other, and can neither assign jobs nor command the fleet.

A show without ``hosts`` runs on one machine, with the top-level endpoints.
"""

from __future__ import annotations

from dataclasses import dataclass

from showfile.bus_view import HostBus, ShowBus

GROUND_ROUTER = "router"
"""Identity of the ground station's router (and of the only router of a one-machine show)."""


class HostError(ValueError):
    """The show's hosts do not match its fleet, or a host name is unknown."""


@dataclass(frozen=True)
class Endpoints:
    """Where one process's session listens and connects."""

    router_listen: tuple[str, ...]
    """Its host router's listen endpoints."""
    connect: tuple[str, ...]
    """Where the process reaches its host's router."""
    router_connect: tuple[str, ...]
    """Where its host's router reaches the ground router (none on the ground station)."""


def _where(show: ShowBus) -> str:
    return str(show.source_path) if show.source_path else f"show {show.show_id}"


def is_router(identity: str) -> bool:
    """Whether ``identity`` is a router's (the ground router or a companion host's)."""
    return identity == GROUND_ROUTER or identity.startswith(f"{GROUND_ROUTER}@")


def ground_host(show: ShowBus) -> str | None:
    """Name of the ground station (None: a one-machine show)."""
    return next((name for name, host in show.zenoh.hosts.items() if host.services), None)


def router_identity(host_name: str, host: HostBus) -> str:
    """Certificate common name of the router of ``host``."""
    return GROUND_ROUTER if host.services else f"{GROUND_ROUTER}@{host_name}"


def companion_routers(show: ShowBus) -> dict[str, tuple[str, ...]]:
    """Each companion router's identity and the vehicles it carries."""
    return {
        router_identity(name, host): host.vehicles
        for name, host in show.zenoh.hosts.items()
        if not host.services
    }


def check_hosts(show: ShowBus) -> None:
    """Raise :class:`HostError` unless every vehicle runs on exactly one host (when hosts are
    given) and every vehicle a host names is in the fleet."""
    if not show.zenoh.hosts:
        return
    fleet = [v.id for v in show.vehicles]
    placed = {vid: name for name, host in show.zenoh.hosts.items() for vid in host.vehicles}
    for vehicle_id, name in placed.items():
        if vehicle_id not in fleet:
            raise HostError(
                f"{_where(show)}: zenoh.hosts.{name}.vehicles: {vehicle_id} is not a vehicle of "
                f"the show ({', '.join(fleet)})"
            )
    missing = [vid for vid in fleet if vid not in placed]
    if missing:
        raise HostError(
            f"{_where(show)}: zenoh.hosts: no host runs {', '.join(missing)} "
            f"(list each vehicle under the vehicles of one host)"
        )


def host_named(show: ShowBus, host_name: str) -> HostBus:
    """The host ``host_name`` of the show (HostError naming the known ones otherwise)."""
    hosts = show.zenoh.hosts
    if host_name not in hosts:
        known = ", ".join(hosts) or "none: the show runs on one machine"
        raise HostError(f"{_where(show)}: no host {host_name!r} in zenoh.hosts ({known})")
    return hosts[host_name]


def host_of(show: ShowBus, identity: str) -> str | None:
    """The host ``identity`` runs on: its vehicle's, its router's, else the ground station."""
    for name, host in show.zenoh.hosts.items():
        if identity in host.vehicles or identity == router_identity(name, host):
            return name
    return ground_host(show)


def endpoints(show: ShowBus, identity: str) -> Endpoints:
    """The endpoints of ``identity``'s session: its host's, or the show's on one machine."""
    name = host_of(show, identity)
    if name is None:
        z = show.zenoh
        return Endpoints(z.router_listen, z.connect, z.router_connect)
    host = show.zenoh.hosts[name]
    return Endpoints(host.router_listen, host.local_connect, host.router_connect)


def all_endpoints(show: ShowBus) -> list[str]:
    """Every endpoint the show names (for the routers' certificates)."""
    z = show.zenoh
    found = [*z.router_listen, *z.connect, *z.router_connect]
    for host in z.hosts.values():
        found += [*host.router_listen, *host.local_connect, *host.router_connect]
    return found

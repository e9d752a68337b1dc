"""The vehicles of a show file that fly over MAVLink, as simulated vehicle configurations.

A vehicle with ``backend: mavlink`` and ``mavlink_url: udp:HOST:PORT`` (or ``udpout:``) becomes a
simulated ArduCopter listening on HOST:PORT, system id ``mavlink_system_id`` (default: its index
in the show + 1), starting at its ``home_m_enu`` (also its LOCAL_NED origin), with the show's mass
and thrust limits. A vehicle that forwards mocap (``mavlink_mocap``) boots with the parameters its
autopilot reads only at boot to fuse it (:data:`mavsim.mocap.MOCAP_BOOT_PARAMS`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

from mavsim.config import PositionGains, VehicleConfig
from mavsim.errors import MavsimError
from mavsim.mocap import MOCAP_BOOT_PARAMS

SERVED_SCHEMES = ("udp", "udpout")


def endpoint_of(url: str) -> tuple[str, int]:
    """(host, port) the simulated vehicle binds for a companion's ``udp:HOST:PORT`` url."""
    scheme, _, rest = url.strip().partition(":")
    host, _, port = rest.removeprefix("//").rpartition(":")
    if scheme.lower() not in SERVED_SCHEMES or not host:
        raise MavsimError(
            f"mavlink_url {url!r}: the simulator serves udp:HOST:PORT endpoints only "
            "(the companion sends first, the vehicle answers)"
        )
    try:
        return host, int(port)
    except ValueError:
        raise MavsimError(f"mavlink_url {url!r}: port {port!r} is not a number") from None


def vehicle_configs(
    show: Any,
    *,
    only: set[str] | None = None,
    gains: PositionGains | None = None,
    arm_refusals: Mapping[str, str] | None = None,
    **overrides: Any,
) -> list[VehicleConfig]:
    """One config per MAVLink vehicle of ``show`` (a ``showfile.Show``), optionally ``only``
    those ids; ``overrides`` set further :class:`VehicleConfig` fields on every vehicle."""
    configs: list[VehicleConfig] = []
    refusals = dict(arm_refusals or {})
    for index, vehicle in enumerate(show.vehicles):
        if vehicle.backend != "mavlink" or (only is not None and vehicle.id not in only):
            continue
        host, port = endpoint_of(vehicle.mavlink_url)
        limits = vehicle.limits if vehicle.limits is not None else show.limits
        config = VehicleConfig(
            vehicle_id=vehicle.id,
            system_id=vehicle.mavlink_system_id or index + 1,
            host=host,
            port=port,
            home_m_enu=tuple(float(v) for v in vehicle.home_m_enu),  # type: ignore[arg-type]
            mass_kg=float(limits.mass_kg),
            thrust_max_n=float(limits.thrust_max_n),
            arm_refusal=refusals.pop(vehicle.id, None),
            **overrides,
        )
        if vehicle.mavlink_mocap != "none":
            boot = MOCAP_BOOT_PARAMS[config.autopilot]
            config = replace(config, params=(*boot, *config.params))
        configs.append(config if gains is None else replace(config, gains=gains))
    if refusals:
        raise MavsimError(
            f"--refuse-arm names vehicles that are not MAVLink ones: {sorted(refusals)}"
        )
    if only is not None and {c.vehicle_id for c in configs} != only:
        missing = sorted(only - {c.vehicle_id for c in configs})
        raise MavsimError(f"not MAVLink vehicles of the show: {missing}")
    return configs

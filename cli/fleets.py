"""Which vehicles of a host run in fleet hosts (pure): the show's ``fleet_hosts``."""

from __future__ import annotations

from collections.abc import Sequence

from showfile import Show


def split_fleets(
    show: Show, vehicle_ids: Sequence[str]
) -> tuple[tuple[str, ...], tuple[tuple[str, ...], ...]]:
    """``vehicle_ids`` as (vehicles with an agent process each, groups of one fleet host each).

    With ``fleet_hosts: N`` the simulated vehicles are dealt round-robin, in show order, into at
    most N groups (so that vehicles busy at the same time, often neighbours in the list, spread
    over the hosts and their cores); real (MAVLink) vehicles always keep their own agent.
    Without it, every vehicle has its own agent, as before."""
    if show.fleet_hosts == 0:
        return tuple(vehicle_ids), ()
    simulated = [v for v in vehicle_ids if show.vehicle(v).backend == "sim"]
    alone = tuple(v for v in vehicle_ids if show.vehicle(v).backend != "sim")
    count = min(show.fleet_hosts, len(simulated))
    groups = tuple(tuple(simulated[i::count]) for i in range(count))
    return alone, groups

"""A show's MAVLink vehicle: its
:class:`~vehicle_agent.backends.mavlink.backend.MavlinkBackend` built
from the agent's :class:`~vehicle_agent.setup.VehicleSetup`.

The settings come from the vehicle's ``mavlink_*`` fields; its kind's room gives the pen it
carries (modelled from its pose, contact only over its board) and the mocap's latency and noise;
the show's safety section may add the autopilot's own fence around the agent's geofence.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from vehicle_agent.backends.mavlink.backend import MavlinkBackend
from vehicle_agent.backends.mavlink.params import autopilot_fence
from vehicle_agent.backends.mavlink.pen import PenOverBoard
from vehicle_agent.backends.mavlink.settings import settings_from_show
from vehicle_agent.setup import VehicleSetup, autopilot_world, on_board


def create_backend(setup: VehicleSetup, **kwargs: Any) -> MavlinkBackend:
    """The backend of ``setup`` (a :class:`vehicle_agent.agent.VehicleSetup` whose vehicle has
    ``backend: mavlink``), carrying its kind's pen over its board and, as a second line, the
    autopilot's own fence around the agent's geofence; ``kwargs`` go to :class:`MavlinkBackend`
    (``on_text``, ``mocap_source``)."""
    show = setup.show
    vehicle = show.vehicle(setup.vehicle_id)
    settings = settings_from_show(show, vehicle)
    fence = setup.runner_config.safety.fence
    if show.safety.autopilot_fence and fence is not None:
        settings = replace(
            settings,
            fence=autopilot_fence(
                fence, settings.origin_m_enu, show.safety.autopilot_fence_margin_m
            ),
        )
    world = autopilot_world(setup)
    settings = replace(settings, mocap_latency_s=world.mocap_latency_s,
                       mocap_noise_std_m=world.mocap_noise_std_m)  # fmt: skip
    kwargs.setdefault("pen", PenOverBoard(world.pen, on_board(setup)))
    return MavlinkBackend(settings, **kwargs)

"""Connecting to an autopilot: the handshake, the telemetry asked for, the show's parameters.

We announce ourselves as a ground station (HEARTBEAT MAV_TYPE_GCS every
:data:`GCS_HEARTBEAT_PERIOD_S`: PX4 sends STATUSTEXT only to links where it hears one) until the
autopilot's heartbeat comes (system and component id from it, ArduPilot or PX4 from its
``autopilot`` field; anything else is refused), ask for position/attitude telemetry at the
telemetry rate and the slow system messages (the estimator's status among them) at 1 Hz, then
set and read back the parameters the show depends on
(:mod:`~vehicle_agent.backends.mavlink.params`); one that does not hold is the vehicle's fault.
:class:`~vehicle_agent.backends.mavlink.backend.MavlinkBackend` calls these at ``start``.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable

from vehicle_agent.backends.mavlink.commands import CommandChannel
from vehicle_agent.backends.mavlink.errors import LinkLostError, UnsupportedAutopilotError
from vehicle_agent.backends.mavlink.health import ESTIMATOR_MESSAGE
from vehicle_agent.backends.mavlink.link import MavlinkLink
from vehicle_agent.backends.mavlink.params import (
    Flavor,
    ParamChannel,
    ParamError,
    mocap_params,
    show_params,
)
from vehicle_agent.backends.mavlink.settings import MavlinkSettings
from vehicle_agent.backends.mavlink.state import MAV_AUTOPILOT_INVALID, MAV_TYPE_GCS, LinkState

CMD_SET_MESSAGE_INTERVAL = 511
STREAMED = {32: "LOCAL_POSITION_NED", 30: "ATTITUDE", 85: "POSITION_TARGET_LOCAL_NED"}
SLOW = {1: "SYS_STATUS", 147: "BATTERY_STATUS", 245: "EXTENDED_SYS_STATE"}
GCS_HEARTBEAT_PERIOD_S = 0.5
"""Our heartbeat period in [s]: PX4 drops a ground station unheard for 2.5 s (and its texts with
it), so a stall of the agent of up to 2 s keeps the texts coming."""


def send_gcs_heartbeat(link: MavlinkLink) -> None:
    """One HEARTBEAT of ours on ``link``."""
    # a ground station (PX4 sends STATUSTEXT only then), no autopilot, MAV_STATE_ACTIVE
    hb = link.mav.heartbeat_encode(MAV_TYPE_GCS, MAV_AUTOPILOT_INVALID, 0, 0, 4)
    link.send(hb)


async def await_autopilot(
    state: LinkState,
    heard: asyncio.Event,
    send_heartbeat: Callable[[], None],
    *,
    url: str,
    timeout_s: float,
) -> None:
    """Send our heartbeat until ``state`` has the autopilot's (``heard`` is set on each one).

    Raises :class:`LinkLostError` when none came from ``url`` within ``timeout_s`` in [s], and
    :class:`UnsupportedAutopilotError` for an autopilot neither ArduPilot nor PX4.
    """
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout_s
    while not state.connected:
        send_heartbeat()
        if loop.time() >= deadline:
            raise LinkLostError(f"no autopilot heartbeat on {url} within {timeout_s:.0f} s")
        try:
            await asyncio.wait_for(heard.wait(), timeout=0.5)
        except TimeoutError:
            continue
    if state.flavor is None:
        raise UnsupportedAutopilotError(
            f"autopilot type {state.autopilot} on {url} is neither ArduPilot nor PX4"
        )


def request_telemetry(
    commands: CommandChannel, rate_hz: float, truth_message: int | None, flavor: str
) -> None:
    """Ask for position and attitude (and the simulator's ``truth_message``, if any) at
    ``rate_hz`` in [Hz], the system and battery state and the ``flavor``'s estimator status
    (``health.ESTIMATOR_MESSAGE``) at 1 Hz."""
    fast_us = 1e6 / rate_hz
    for message_id in STREAMED:
        commands.send(CMD_SET_MESSAGE_INTERVAL, message_id, fast_us)
    for message_id in (*SLOW, ESTIMATOR_MESSAGE[flavor]):
        commands.send(CMD_SET_MESSAGE_INTERVAL, message_id, 1e6)
    if truth_message is not None:
        commands.send(CMD_SET_MESSAGE_INTERVAL, truth_message, fast_us)


async def set_show_params(
    params: ParamChannel, settings: MavlinkSettings, flavor: Flavor, into: dict[str, float]
) -> str | None:
    """Set and read back every parameter the show needs, each held one into ``into`` by name;
    the fault when one does not hold (the later ones are not tried), None when all do."""
    specs = show_params(
        flavor, setpoint_timeout_s=settings.setpoint_timeout_s, fence=settings.fence
    )
    if settings.mocap != "none":
        specs += mocap_params(flavor, with_velocity=settings.mocap == "odometry")
    for spec in specs:
        try:
            into[spec.name] = await params.ensure(spec)
        except ParamError as exc:
            return f"parameters not set, vehicle refused: {exc}"
    return None

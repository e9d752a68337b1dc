"""The crew's battery swap on an autopilot: what the agent tells it after the crew's
``battery_swapped`` (the orchestrator lets the vehicle fly again once a fuller pack reports).

- ArduPilot counts the charge drawn since boot and reports what is left from that count
  (``AP_BattMonitor_Backend::capacity_remaining_pct``). A real swap restarts the autopilot, which
  starts a new count; a pack changed without a restart (or SITL, whose pack nobody changes) keeps
  the old count until MAV_CMD_BATTERY_RESET (42651: param1 the mask of batteries, param2 the
  percentage left; ``GCS_MAVLINK::handle_command_battery_reset``). The agent sends it for the
  first battery, the one BATTERY_STATUS id 0 reports, at 100 %: after a restart it changes
  nothing. ArduPilot accepts it armed too; the agent sends it only disarmed on the ground.
- PX4 (v1.16) has no handler for 42651 (Commander answers UNSUPPORTED, with a negative tune on
  a real vehicle), so nothing is sent: a real PX4 is restarted by the swap and estimates the new
  pack from its voltage, and PX4 SITL's simulated pack is full whenever it is disarmed
  (``BatterySimulator::Run``), so its swap ends with the next status after landing.
"""

from __future__ import annotations

from vehicle_agent.backends.base import BackendError
from vehicle_agent.backends.mavlink.commands import CommandChannel
from vehicle_agent.backends.mavlink.state import MAV_LANDED_STATE_ON_GROUND, LinkState

CMD_BATTERY_RESET = 42651
FIRST_BATTERY_MASK = 1.0
"""param1 of MAV_CMD_BATTERY_RESET: bit 0, the first battery."""
FULL_PERCENT = 100.0
"""param2: the charge left in the fresh pack, [%]."""


def swap_refusal(state: LinkState) -> str | None:
    """Why the autopilot of ``state`` may not be told of a fresh pack now (None: it may)."""
    if not state.connected:
        return "no link to the autopilot"
    if state.armed:
        return "its motors are armed"
    if state.landed_state not in (None, MAV_LANDED_STATE_ON_GROUND):
        return "the autopilot does not say it is on the ground"
    return None


async def reset_after_swap(commands: CommandChannel, state: LinkState) -> None:
    """Tell the autopilot of ``state`` that a full pack is in, where it keeps a count to reset
    (ArduPilot); raises :class:`BackendError` when it may not be told now or refuses."""
    why_not = swap_refusal(state)
    if why_not is not None:
        raise BackendError(f"battery not reset: {why_not}")
    flavor = state.flavor
    if flavor is not None and flavor.name == "ardupilot":
        await commands.run(CMD_BATTERY_RESET, FIRST_BATTERY_MASK, FULL_PERCENT)

"""Typed errors of the MAVLink backend; all are :class:`BackendError` so the agent catches them."""

from __future__ import annotations

from vehicle_agent.backends.base import BackendError, CommandRefusedError, NotReadyError

MAV_RESULT_NAMES = {0: "ACCEPTED", 1: "TEMPORARILY_REJECTED", 2: "DENIED", 3: "UNSUPPORTED",
                    4: "FAILED", 5: "IN_PROGRESS", 6: "CANCELLED"}  # fmt: skip
COMMAND_ARM_DISARM, MAV_RESULT_TEMPORARILY_REJECTED = 400, 1
COMMAND_NAMES = {11: "SET_MODE", 21: "NAV_LAND", 22: "NAV_TAKEOFF", 176: "DO_SET_MODE",
                 179: "DO_SET_HOME", 400: "COMPONENT_ARM_DISARM",
                 511: "SET_MESSAGE_INTERVAL"}  # fmt: skip


class MavlinkError(BackendError):
    """Root of the MAVLink backend's errors."""


class LinkLostError(MavlinkError):
    """No heartbeat from the autopilot (at start, or for longer than the timeout)."""


class UnsupportedAutopilotError(MavlinkError):
    """The heartbeat names an autopilot other than ArduPilot or PX4."""


class CommandTimeoutError(MavlinkError):
    """A command got no COMMAND_ACK after every attempt."""


class CommandRejectedError(MavlinkError, CommandRefusedError):
    """The autopilot answered a command with a result other than ACCEPTED (it is still healthy)."""

    def __init__(self, command: int, result: int, reason: str | None) -> None:
        self.command = command
        self.result = result
        self.reason = reason
        """The autopilot's own words (its STATUSTEXT around the refusal), when it said any."""
        name = COMMAND_NAMES.get(command, str(command))
        outcome = MAV_RESULT_NAMES.get(result, str(result))
        because = f": {reason}" if reason else ""
        super().__init__(f"autopilot refused {name} ({outcome}){because}")


class ArmingRefusedError(CommandRejectedError):
    """Arming was refused (pre-arm checks: no position estimate yet, ...)."""


class PrearmFailingError(ArmingRefusedError, NotReadyError):
    """Arming was not asked for: the autopilot says its pre-arm checks fail (SYS_STATUS), and
    ``reason`` is its explanation; an ARM now would only be refused."""

    def __init__(self, reason: str) -> None:
        super().__init__(COMMAND_ARM_DISARM, MAV_RESULT_TEMPORARILY_REJECTED, reason)
        self.args = (f"not arming: the autopilot's pre-arm checks fail: {reason}",)


class VehicleFaultError(MavlinkError):
    """A command while the vehicle is in a fault (pilot has control, link lost, failsafe)."""


def off_the_mocap_reason(off_m: float) -> str:
    """Why a vehicle whose position estimate is ``off_m`` [m] from the mocap does not take off."""
    return (
        f"the autopilot's position estimate is {off_m:.2f} m from the mocap's (its estimator"
        " has not taken the mocap yet: restart the autopilot if it stays so)"
    )


class EstimateOffMocapError(MavlinkError, NotReadyError):
    """Nothing was asked of the vehicle: its position estimate is not where the mocap poses we
    send put it (its estimator has not taken them yet: PX4 SIH's first seconds, 4.5 m off; EKF2
    with a barometer height, 583 m off); a take-off would climb from the wrong place. The
    vehicle's preflight says so too, until the estimate comes to the mocap."""

    def __init__(self, off_m: float) -> None:
        super().__init__(f"not arming: {off_the_mocap_reason(off_m)}")
        self.off_m = off_m

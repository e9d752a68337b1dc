"""Settings of one MAVLink vehicle, typed and frozen; built from the show file once."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from showfile import Show, Vehicle
from vehicle_agent.backends.base import BackendError, Vec3
from vehicle_agent.backends.mavlink.params import FenceSpec

MocapMessage = Literal["none", "vision_position_estimate", "att_pos_mocap", "odometry"]
TruthSource = Literal["none", "sitl"]


@dataclass(frozen=True)
class MavlinkSettings:
    """How the agent talks to one autopilot."""

    url: str
    """Where the autopilot is (see :mod:`vehicle_agent.backends.mavlink.url`)."""
    origin_m_enu: Vec3
    """Where the vehicle's LOCAL_NED origin (its estimator's home) is in the show frame, [m]."""
    system_id: int | None = None
    """The autopilot's system id; None: the first autopilot heartbeat on the link."""
    control_rate_hz: float = 100.0
    """Rate of ``tick`` (the agent's control loop) in [Hz]."""
    setpoint_rate_hz: float = 50.0
    """Rate of the setpoint stream in [Hz] (50-100; ArduPilot follows 50 Hz well)."""
    telemetry_rate_hz: float = 50.0
    """Rate asked for LOCAL_POSITION_NED and ATTITUDE (MAV_CMD_SET_MESSAGE_INTERVAL)."""
    heartbeat_timeout_s: float = 3.0
    """No autopilot heartbeat for this long -> fault (lost link)."""
    connect_timeout_s: float = 10.0
    """How long ``start`` waits for the first heartbeat."""
    command_timeout_s: float = 1.0
    """How long one attempt of a command waits for its COMMAND_ACK."""
    command_attempts: int = 3
    """Attempts per command before it times out."""
    setpoint_timeout_s: float = 1.0
    """The autopilot's setpoint timeout in [s], set at connect (ArduPilot GUID_TIMEOUT, PX4
    COM_OF_LOSS_T; 0.5..1 s): a longer gap in our stream is a fault."""
    set_params: bool = True
    """Set and verify the parameters the show needs at connect (params.show_params);
    a vehicle whose parameters cannot be set is in fault."""
    fence: FenceSpec | None = None
    """The autopilot's own fence around its home, set at connect (None: left as it is)."""
    takeoff_tolerance_m: float = 0.1
    """Height error in [m] under which the take-off is complete."""
    takeoff_timeout_s: float = 30.0
    """A take-off not complete after this long is a fault."""
    land_timeout_s: float = 60.0
    """A landing not finished (disarmed on the ground) after this long is a fault."""
    climb_speed_mps: float = 0.5
    """Climb rate of our own take-off ramp (PX4 OFFBOARD) in [m/s]."""
    mocap: MocapMessage = "none"
    """Forward motion-capture poses from ``mocap_source`` with this message."""
    mocap_rate_hz: float = 50.0
    """Rate of forwarded mocap poses in [Hz]."""
    truth: TruthSource = "none"
    """``sitl``: read the simulator's true state off the link (ArduPilot SIM_STATE, PX4
    HIL_STATE_QUATERNION); the pen model and the job metrics use it, and with ``mocap`` it is the
    mocap source (with ``mocap_latency_s`` and ``mocap_noise_std_m``)."""
    mocap_latency_s: float = 0.005
    """Age in [s] of a mocap pose made from the truth."""
    mocap_noise_std_m: float = 0.0002
    """Noise in [m] per axis of a mocap pose made from the truth."""
    lead_s: float | None = None
    """How far in [s] ahead on the plan position setpoints are sent, to cancel the autopilot's
    lag; None: identified in flight (:mod:`~vehicle_agent.backends.mavlink.lag`)."""

    def __post_init__(self) -> None:
        for name in ("control_rate_hz", "setpoint_rate_hz", "telemetry_rate_hz",
                     "heartbeat_timeout_s", "connect_timeout_s", "command_timeout_s",
                     "mocap_rate_hz", "climb_speed_mps"):  # fmt: skip
            if not getattr(self, name) > 0:
                raise BackendError(f"mavlink setting {name} must be > 0")
        if self.setpoint_rate_hz > self.control_rate_hz:
            raise BackendError("mavlink setpoint_rate_hz cannot exceed the control rate")
        if self.command_attempts < 1:
            raise BackendError("mavlink command_attempts must be >= 1")
        if self.lead_s is not None and not 0.0 <= self.lead_s <= 0.5:
            raise BackendError("mavlink lead_s must be in 0..0.5 s")
        if self.mocap_latency_s < 0 or self.mocap_noise_std_m < 0:
            raise BackendError("mavlink mocap latency and noise must be >= 0")
        if not 0.1 <= self.setpoint_timeout_s <= 10.0:
            raise BackendError("mavlink setpoint_timeout_s must be in 0.1..10 s")

    @property
    def control_period_s(self) -> float:
        return 1.0 / self.control_rate_hz


def settings_from_show(
    show: Show, vehicle: Vehicle, fence: FenceSpec | None = None
) -> MavlinkSettings:
    """Settings of ``vehicle`` (a show-file vehicle with ``backend: mavlink``) in ``show``: its
    ``mavlink_*`` fields (origin default: its home) and the show's control rate;
    ``fence``: the autopilot's own fence (see ``create_backend``)."""
    if not vehicle.mavlink_url:
        raise BackendError(f"vehicle {vehicle.id}: backend mavlink needs mavlink_url")
    origin = vehicle.mavlink_origin_m_enu or vehicle.home_m_enu
    return MavlinkSettings(
        url=vehicle.mavlink_url,
        origin_m_enu=(float(origin[0]), float(origin[1]), float(origin[2])),
        system_id=vehicle.mavlink_system_id,
        control_rate_hz=float(show.controller.rate_hz),
        telemetry_rate_hz=float(show.controller.rate_hz),
        setpoint_rate_hz=float(vehicle.mavlink_setpoint_rate_hz),
        mocap=vehicle.mavlink_mocap,
        truth=vehicle.mavlink_truth,
        lead_s=vehicle.mavlink_lead_s,
        fence=fence,
    )

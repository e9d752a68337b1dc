"""Typed, frozen models of a show file (pydantic v2). Loaded once by :func:`showfile.load_show`.

World frame ENU, SI units; angles in the file are in degrees (``yaw_deg``) for people, exposed in
radians (``yaw_rad``) for code.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import (
    AfterValidator,
    Field,
    field_validator,
    model_validator,
)
from pydantic_core import PydanticCustomError

from showfile import paths
from showfile.model_base import ID_PATTERN, Identifier, ShowModel
from showfile.safety import SafetySettings
from showfile.security import RESERVED_IDS, SecuritySettings
from showfile.services import (
    BatterySettings,
    KioskSettings,
    PolicySettings,
    PreflightSettings,
    StorageSettings,
    ZenohSettings,
)
from vehicles import DEFAULT_KIND, ROOMS, UnknownKindError
from vehicles.hexarotor_sponge.show_section import HexarotorKindSettings
from vehicles.omni_wheel.show_section import OmniWheelSettings
from vehicles.quadrotor_brush.gain_names import GAIN_NAMES

Vec3 = tuple[float, float, float]
Size2 = tuple[float, float]


class Board(ShowModel):
    """A writing board: its writing area is centred on ``center_m_enu``."""

    id: Identifier = Field(pattern=ID_PATTERN)
    """Board identifier, referenced by vehicles."""
    center_m_enu: Vec3
    """Centre of the writing area on the board surface, in [m], world ENU."""
    yaw_deg: float = 0.0
    """Rotation of the board's x axis about world z, in [deg] (counter-clockwise from east)."""
    orientation: Literal["horizontal", "vertical", "floor"] = "horizontal"
    """``horizontal`` (table, brush from above), ``vertical`` (wall), ``floor`` (ground)."""
    size_m: Size2
    """Board extent along its own x and y (vertical: width and height), in [m]."""
    writing_area_m: Size2
    """Extent of the area glyphs are laid out in, centred on the board, in [m]."""
    sheets: Literal["per_character", "when_spoiled", "none"] = "when_spoiled"
    """When the crew changes the sheet: after every character (``per_character``: the visitor
    takes it away, as at the Airshow), only after a half-written one (``when_spoiled``), or never
    (``none``: a surface that clears itself, e.g. water on a cloth, after ``dry_s``)."""
    dry_s: float = Field(default=0.0, ge=0.0)
    """With ``sheets: none``: show seconds after a character before the board is written on
    again (the surface dries)."""

    @property
    def yaw_rad(self) -> float:
        """``yaw_deg`` in [rad]."""
        return math.radians(self.yaw_deg)

    @model_validator(mode="after")
    def _positive_sizes(self) -> Board:
        for name in ("size_m", "writing_area_m"):
            if min(getattr(self, name)) <= 0.0:
                raise ValueError(f"{name} must be positive")
        if self.dry_s > 0.0 and self.sheets != "none":
            raise ValueError("dry_s goes with sheets: none (a sheet changed needs no drying)")
        return self


def _known_kind(name: str) -> str:
    if name not in ROOMS:
        # the registry's own message, without pydantic's "Value error, " in front
        raise PydanticCustomError(
            "unknown_kind", "{reason}", {"reason": str(UnknownKindError(name))}
        )
    return name


def _list_kinds(schema: dict[str, Any]) -> None:
    schema["enum"] = sorted(ROOMS)


KindName = Annotated[str, AfterValidator(_known_kind), Field(json_schema_extra=_list_kinds)]
"""The name of a vehicle kind that has a room (``vehicles.ROOMS``; README.md, "Where things are":
``vehicles/``); any other is refused naming the kinds. The JSON schema lists them."""


class Limits(ShowModel):
    """Dynamic limits of the brush quadrotor (``quadrotor-brush``): its planner's
    (planner.limits.VehicleLimits), its pen-up moves and its MAVLink simulator's vehicle. The
    hexarotor and the ground writer read none of them (their limits are in their own sections,
    ``hexarotor`` and ``omni_wheel``), but for the show's ``v_max_mps`` in the orchestrator's rough
    duration of a job not yet planned. Each field says who reads it ("Read by:"). The defaults are
    the planner's own (one set for shows, ``plan`` and ``fly``; tests/test_vehicles_jobs.py holds
    them equal; the show file cannot import the planner, which the console and trust must not
    see)."""

    a_max_mps2: Vec3 = (0.8, 0.8, 0.5)
    """Largest acceleration per world axis x, y, z, in [m/s^2]. Read by: quadrotor-brush (its
    plan; the smallest axis, its pen-up moves)."""
    v_max_mps: float = Field(default=0.5, gt=0.0)
    """Largest speed, in [m/s]. Read by: quadrotor-brush (its plan and pen-up moves); the show's
    value, for every kind, by the orchestrator's rough duration of a job not yet planned."""
    mass_kg: float = Field(default=1.0, gt=0.0)
    """Vehicle mass, in [kg] (the Airshow quadrotors were about 1 kg). Read by: quadrotor-brush
    (its plan's thrust limit; the MAVLink simulator's vehicle)."""
    thrust_max_n: float = Field(default=19.6133, gt=0.0)
    """Largest total thrust, in [N]. Read by: quadrotor-brush (its plan; the MAVLink simulator's
    vehicle)."""
    body_rate_max_radps: float = Field(default=3.0, gt=0.0)
    """Largest body rate, in [rad/s]. Read by: quadrotor-brush."""

    @model_validator(mode="after")
    def _positive_acceleration(self) -> Limits:
        if min(self.a_max_mps2) <= 0.0:
            raise ValueError("a_max_mps2 must be positive on every axis")
        return self


class PlanningSettings(ShowModel):
    """How a job is planned on its board: ``margin_m`` for every kind, ``clearance_m`` for the
    airborne kinds, the rest the brush quadrotor's planner options (planner.options.PlanOptions).
    The hexarotor and the ground writer plan with their own sections (``hexarotor``,
    ``omni_wheel``) and their rooms' figures. Each field says who reads it ("Read by:"). The
    defaults are ``planner.defaults`` (held equal by tests/test_vehicles_jobs.py)."""

    write_height_m: float = Field(default=0.335, gt=0.0)
    """Height of the vehicle reference point above the board surface while writing, in [m].
    Read by: quadrotor-brush (its plan, its brush's length, its controller's lever and its pen-up
    height)."""
    clearance_m: float = Field(default=0.05, ge=0.0)
    """Extra height with the pen up, in [m]. Read by: quadrotor-brush (between strokes and on its
    way, above the write height) and hexarotor-sponge (its pen-up moves, above the top of its
    wall's writing area)."""
    margin_m: float = Field(default=0.05, ge=0.0)
    """Margin kept free inside the writing area when a glyph is fitted to it, in [m].
    Read by: every kind (the layout of a job on any board, wall or floor; the hexarotor's reach
    check)."""
    split_threshold_m: float = Field(default=0.01, gt=0.0)
    """Split-and-merge tolerance for turning points, in [m]. Read by: quadrotor-brush."""
    resegment: bool = True
    """Re-time the segments (with ``pace: limits``, at the limits; with ``nominal``, the paper's
    re-segmentation from a conservative start). Read by: quadrotor-brush."""
    pace: Literal["limits", "nominal", "tracking"] = "limits"
    """``limits``: as fast as the limits allow (within ~1.25x of time-optimal); ``nominal``: the
    earlier, slower default (about 2x); ``tracking``: planned at the limits, then each job flown
    just slow enough that the vehicle's own tracking, identified from the jobs it flew
    (planner.pace, kept in ``<database dir>/tracking/<vehicle>.json``), is predicted to write
    within ``pace_rmse_target_m``. Read by: quadrotor-brush (``limits``, ``nominal``), every kind's
    agent (``tracking``)."""
    pace_rmse_target_m: float = Field(default=0.006, gt=0.0)
    """With ``pace: tracking``: the pen-down RMSE in [m] a job's pace aims at. 6 mm: on the
    brush quadrotor's 2 cm ink line, jobs written at 3.8-6.6 mm reached IoU 0.78-0.85 and those at
    7.3-11 mm 0.60-0.72 (README's SITL and simulator measurements), so 6 mm aims at an IoU of
    0.75 with room for the prediction's own error. Read by: every kind's agent."""
    pace_first_stretch: float = Field(default=2.0, ge=1.0)
    """With ``pace: tracking``: how many times slower than the limits a vehicle flies while its
    tracking is not yet identified (its first job). 2: PX4 SIH wrote a 1.2 m character 13-20 mm
    off and the same at 0.6 m, half the speed and acceleration at the same time, 8-11 mm (issue
    31's measurement). A vehicle whose error pace does not buy back flies its first job at
    ``pace_max_stretch`` (``shows/sitl-px4.yaml``). Read by: every kind's agent."""
    pace_max_stretch: float = Field(default=4.0, ge=1.0)
    """With ``pace: tracking``: the slowest a job is flown, times the limits' duration, even when
    the target is below what the vehicle can reach (its prediction then says so). Read by:
    every kind's agent."""
    solver: Literal["piqp", "clarabel"] = "piqp"
    """QP solver of the acceleration-limited fit. Read by: quadrotor-brush."""
    sample_rate_hz: float = Field(default=100.0, ge=100.0)
    """Rate the trajectory is sampled at for the control loop, in [Hz]. Read by: quadrotor-brush
    (the kiosk's preview replaces it with its own)."""
    total_time_s: float | None = Field(default=None, gt=0.0)
    """Fixed duration of a character, or None to let the planner choose, in [s].
    Read by: quadrotor-brush."""

    @model_validator(mode="after")
    def _first_within_max(self) -> PlanningSettings:
        if self.pace_first_stretch > self.pace_max_stretch:
            raise ValueError(
                f"pace_first_stretch {self.pace_first_stretch} is above pace_max_stretch "
                f"{self.pace_max_stretch}"
            )
        return self


class ControllerSettings(ShowModel):
    """Outer-loop controller of the brush quadrotor, and the loop rate of the vehicles flown
    behind an autopilot (MAVLink; today the brush quadrotor alone). The hexarotor and the ground
    writer have their controllers and their 100 Hz loops in their rooms. Each field says who
    reads it ("Read by:")."""

    preset: Literal["default", "paper"] = "default"
    """``paper``: the RPT gains of the Airshow paper; ``default``: the project's tuned gains.
    Read by: quadrotor-brush (with ``backend: sim``; an autopilot flies its own gains)."""
    rate_hz: float = Field(default=100.0, gt=0.0)
    """Control loop rate, in [Hz]. Read by: quadrotor-brush (its simulated world's tick; with
    ``backend: mavlink``, the agent's loop and telemetry, and the bound of the vehicle's
    ``mavlink_setpoint_rate_hz``)."""
    overrides: dict[str, float] = Field(default_factory=dict)
    """RPT design parameters replacing the preset's, per world axis: ``<axis>.<parameter>`` with
    axis ``x``, ``y`` or ``z`` and parameter ``eps``, ``wn_radps``, ``zeta`` or ``ki_radps``
    (eq. 9 of the Airshow paper), each positive, e.g. ``{z.eps: 0.8}``. Read by:
    quadrotor-brush (with ``backend: sim``; an autopilot flies its own gains)."""

    @field_validator("overrides")
    @classmethod
    def _known_gains(cls, overrides: dict[str, float]) -> dict[str, float]:
        for name, value in overrides.items():
            if name not in GAIN_NAMES:
                why = f"unknown gain {name!r}; the gains are: {', '.join(GAIN_NAMES)}"
            elif not (math.isfinite(value) and value > 0.0):
                why = f"gain {name!r} must be positive and finite, got {value!r}"
            else:
                continue
            raise PydanticCustomError("bad_gain", "{reason}", {"reason": why})
        return overrides


class Vehicle(ShowModel):
    """One vehicle and the board it writes on."""

    id: Identifier = Field(pattern=ID_PATTERN)
    """Vehicle identifier (also in its Zenoh keys)."""

    @field_validator("id")
    @classmethod
    def _not_a_role(cls, value: str) -> str:
        if value in RESERVED_IDS:
            raise ValueError(
                f"vehicle id {value!r} is reserved (a role or key folder: "
                f"{', '.join(sorted(RESERVED_IDS))})"
            )
        return value

    kind: KindName = Field(default=DEFAULT_KIND, validate_default=True)
    """What kind of vehicle it is: one of the kinds that have a room (``vehicles.ROOMS``)."""
    backend: Literal["sim", "mavlink"] = "sim"
    """``sim``: the in-process simulator; ``mavlink``: an autopilot at ``mavlink_url``."""
    board: Identifier
    """Id of the board it writes on."""
    home_m_enu: Vec3
    """Take-off and landing point, in [m], world ENU."""
    mavlink_url: str | None = None
    """pymavlink connection string, e.g. ``udpin:127.0.0.1:14550`` (mavlink backend only)."""
    mavlink_system_id: int | None = Field(default=None, ge=1, le=255)
    """MAVLink system id of the autopilot, when several share a link."""
    mavlink_origin_m_enu: Vec3 | None = None
    """Where the autopilot's LOCAL_NED origin (its estimator's home) is in the show frame, in
    [m], world ENU; None: ``home_m_enu`` (mavlink backend only)."""
    mavlink_setpoint_rate_hz: float = Field(default=50.0, gt=0.0)
    """Rate of the setpoint stream, in [Hz], at most ``controller.rate_hz`` (mavlink only)."""
    mavlink_mocap: Literal["none", "vision_position_estimate", "att_pos_mocap", "odometry"] = "none"
    """Forward motion-capture poses to the autopilot with this message (indoor flight); needs a
    mocap source handed to the backend (mavlink backend only)."""
    mavlink_truth: Literal["none", "sitl"] = "none"
    """``sitl``: the autopilot is a simulator that sends its true state (ArduPilot SIM_STATE, PX4
    HIL_STATE_QUATERNION): job metrics measure it, and it is the mocap source for
    ``mavlink_mocap`` with the show's mocap noise and latency (mavlink backend only)."""
    mavlink_lead_s: float | None = Field(default=None, ge=0.0, le=0.5)
    """How far in [s] ahead on the plan position setpoints are sent, cancelling the autopilot's
    lag; None: identified in flight from the vehicle's response (mavlink backend only)."""
    limits: Limits | None = None
    """Limits of this vehicle, replacing the show's ``limits`` (a brush quadrotor's: the other
    kinds read theirs from their own sections)."""

    @model_validator(mode="after")
    def _mavlink_needs_url(self) -> Vehicle:
        if self.backend == "mavlink" and not self.mavlink_url:
            raise ValueError("backend mavlink needs mavlink_url")
        return self


class MavlinkSimSettings(ShowModel):
    """Simulated MAVLink vehicles for rehearsals (``skyquill sim-mavlink``)."""

    enabled: bool = False
    """``skyquill up`` also runs ``skyquill sim-mavlink SHOW.yaml`` (supervised, started before
    the agents), simulating every ``backend: mavlink`` vehicle on its ``mavlink_url``."""


class Show(ShowModel):
    """A whole show: fleet, boards, endpoints, policies."""

    show_id: Identifier = Field(pattern=ID_PATTERN)
    """Show identifier; the Zenoh namespace ``skyquill/<show_id>/``."""
    title: str = ""
    """Human title for displays."""
    time_scale: float = Field(default=1.0, gt=0.0, le=1000.0)
    """Simulation speed-up: sim backends run this many times faster than real time (tests)."""
    zenoh: ZenohSettings = Field(default_factory=ZenohSettings)
    """Transport settings."""
    security: SecuritySettings = Field(default_factory=SecuritySettings)
    """Identities and access control on the bus (mutual TLS by default)."""
    storage: StorageSettings = Field(default_factory=StorageSettings)
    """Durable state and recordings."""
    policy: PolicySettings = Field(default_factory=PolicySettings)
    """Moderation and queue policy."""
    kiosk: KioskSettings = Field(default_factory=KioskSettings)
    """Public kiosk settings."""
    battery: BatterySettings = Field(default_factory=BatterySettings)
    """The reserve every job must leave in a vehicle's battery, and the crew's swap time."""
    preflight: PreflightSettings = Field(default_factory=PreflightSettings)
    """The bounds of the agent's checks before a vehicle takes jobs (link, mocap, clock)."""
    boards: tuple[Board, ...] = Field(min_length=1)
    """Writing boards."""
    vehicles: tuple[Vehicle, ...] = Field(min_length=1)
    """Vehicles, each assigned to one board."""
    limits: Limits = Field(default_factory=Limits)
    """Dynamic limits of the brush quadrotors (a vehicle's own ``limits`` replaces them); the
    hexarotor and the ground writer have theirs in their sections ``hexarotor`` and
    ``omni_wheel``."""
    planning: PlanningSettings = Field(default_factory=PlanningSettings)
    """How jobs are planned: the layout margin of every kind, the pen-up clearance of the
    airborne kinds, the brush quadrotor's planner options."""
    controller: ControllerSettings = Field(default_factory=ControllerSettings)
    """The brush quadrotor's controller and the loop rate of autopilot-flown vehicles; the
    hexarotor and the ground writer have theirs in their rooms."""
    safety: SafetySettings = Field(default_factory=SafetySettings)
    """Tracking, geofence and writing bounds, and the abort policy (``showfile/safety.py``)."""
    mavlink_sim: MavlinkSimSettings = Field(default_factory=MavlinkSimSettings)
    """Rehearsal: simulate the MAVLink vehicles alongside the show."""
    fleet_hosts: int = Field(default=0, ge=0, le=64)
    """``skyquill up`` runs the simulated vehicles of each host in this many fleet host processes
    (``skyquill fleet``, vehicles split evenly in show order); 0: one agent process each. Real
    vehicles always get an agent of their own."""
    # The kinds' own sections, one per room that has one (``Room.section``; the models live in the
    # rooms, ``vehicles/<room>/show_section.py``; tests/test_showfile_kinds.py holds the two equal).
    hexarotor: HexarotorKindSettings | None = None
    """The ``hexarotor-sponge`` wall writers (vehicle, pen, writing limits); None: defaults."""
    omni_wheel: OmniWheelSettings | None = None
    """The ``omni-wheel`` ground writers (vehicle, writing limits, the steps between the floor
    areas); None: defaults, a flat floor."""

    source_path: Path | None = Field(default=None, exclude=True)
    """The file the show was loaded from (set by load_show, not written in the file); its folder
    is where the show's relative paths start (``showfile/paths.py``)."""

    @property
    def database_path(self) -> Path:
        """SQLite file of the orchestrator (``showfile.paths.database_path``)."""
        return paths.database_path(self.source_path, self.show_id, self.storage.database)

    @property
    def keys_dir(self) -> Path:
        """The show's CA, certificates and private keys (``showfile.paths.keys_dir``)."""
        return paths.keys_dir(
            self.source_path, self.show_id, self.security.keys_dir, self.storage.database
        )

    @property
    def recordings_dir(self) -> Path:
        """Directory of MCAP recordings; default ``out/<show_id>/recordings`` beside the file."""
        default = Path("out") / self.show_id / "recordings"
        return paths.resolve(self.source_path, self.storage.recordings_dir or default)

    def board(self, board_id: str) -> Board:
        """The board with ``board_id``; KeyError listing the known ids otherwise."""
        for board in self.boards:
            if board.id == board_id:
                return board
        raise KeyError(f"no board {board_id!r}; boards: {[b.id for b in self.boards]}")

    def vehicle(self, vehicle_id: str) -> Vehicle:
        """The vehicle with ``vehicle_id``; KeyError listing the known ids otherwise."""
        for vehicle in self.vehicles:
            if vehicle.id == vehicle_id:
                return vehicle
        raise KeyError(f"no vehicle {vehicle_id!r}; vehicles: {[v.id for v in self.vehicles]}")

    def vehicle_limits(self, vehicle_id: str) -> Limits:
        """Limits of one vehicle: its own, or the show's."""
        return self.vehicle(vehicle_id).limits or self.limits

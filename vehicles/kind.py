"""The one small interface through which the agent, the orchestrator, the kiosk preview and the CLI
reach a vehicle kind. Everything that differs between kinds lives in the kind's own room
(``vehicles/<kind>/``) behind a :class:`VehicleKind`; adding a kind means adding a room.

A job flows through a kind the same way for every kind (``vehicles.jobs`` does the first steps)::

    VehicleKind.settings(show, vehicle)     -> the kind's typed settings (limits, world, control)
    glyph (planner.glyphs) -> laid out on the surface (strokes in surface metres)
        -> VehicleKind.plan(...)            -> WritingPlan   (reference + feasibility)
        -> VehicleKind.command_reference(...) what the vehicle's own loop tracks (live agent)
        -> VehicleKind.fly(...) (batch) or the live agent ticking VehicleKind.simulated_vehicle(...)
                                            -> FlownWriting  (the one trace format)
        -> VehicleKind.score(...)           -> WritingScore  (RMSE, IoU, kind-specific figures)
        -> VehicleKind.report(...)          -> report.png

The live agent also asks ``VehicleKind.phases`` how the kind moves between its home and its
writing (take off and land, or drive on the floor; cruise height; pen-up speed and route) and
``VehicleKind.autopilot_world`` what an autopilot-flown vehicle of the kind needs (MAVLink): an
:class:`AutopilotWorld`, the kind's :class:`AutopilotPen` read from the pose the autopilot
reports and the motion capture of its simulated world.

Pure: no transport, no asyncio; a room reads a parsed show only in ``settings``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal, Protocol

if TYPE_CHECKING:
    # annotations only: the registry imports this module, and must not load numpy or the planner
    from collections.abc import Mapping, Sequence

    import numpy as np
    from numpy.typing import NDArray

    from planner.pace import PaceChoice
    from planner.samples import TrajectorySamples
    from showfile.models import Show
    from vehicles.surface import Orientation, Surface, Vec3

    FloatArray = NDArray[np.float64]
    BoolArray = NDArray[np.bool_]
    Mat3 = tuple[Vec3, Vec3, Vec3]
    """A 3x3 matrix by rows."""


@dataclass(frozen=True)
class StrokeInput:
    """One stroke laid out on the writing surface."""

    xy_m: FloatArray
    """(n, 2) points in surface metres, y up for the reader, centred on the writing area."""
    width_m: FloatArray | None = None
    """(n,) wanted line width in [m] per point, or None for the kind's default width."""


@dataclass(frozen=True)
class WritingPlan:
    """A kind's plan of one job: the writing point's reference and its own feasibility report."""

    samples: TrajectorySamples
    """Reference of the writing point (brush tip, sponge tip, marker), world ENU, with pen state;
    ``t = 0`` at rest at the start of the first stroke."""
    strokes: tuple[StrokeInput, ...]
    """The target strokes as laid out on the surface (what the metrics compare against)."""
    surface: Surface
    """Where it is written."""
    force_n: FloatArray | None = None
    """(N,) planned normal contact force in [N] per sample, for kinds that control force."""
    width_m: FloatArray | None = None
    """(N,) planned line width in [m] per sample, where the kind models it."""
    feasibility: Mapping[str, Any] = field(default_factory=dict)
    """The planner's own report: peak acceleration and speed against limits, fit error, solver
    status, iterations, solve time... (JSON-serialisable values)."""
    turning_points_m: tuple[FloatArray, ...] = ()
    """Per stroke, the turning points the planner kept, (k, 2) in surface metres (previews)."""
    detail: object = None
    """The kind's own plan object, for its kind-specific outputs (the brush quadrotor: the
    ``planner.pipeline.PlannedTrajectory`` behind ``TRAJ.json`` and the plan plot)."""
    pace: PaceChoice | None = None
    """How much slower than planned ``samples`` fly, to the vehicle's identified tracking
    (show ``planning.pace: tracking``, ``vehicle_agent/pace.py``); None: flown as planned
    (``detail`` is then the unstretched plan)."""

    @property
    def duration_s(self) -> float:
        """Planned writing time in [s]."""
        return self.samples.duration_s


@dataclass(frozen=True)
class FlownWriting:
    """What was flown or driven while writing, one row per control tick (true values)."""

    t_s: FloatArray
    """(K,) time in [s] since writing started."""
    reference_m_enu: FloatArray
    """(K, 3) reference of the writing point in [m], ENU."""
    writing_point_m_enu: FloatArray
    """(K, 3) true writing point (tip) in [m], ENU."""
    pen_down: BoolArray
    """(K,) the reference meant the pen to touch."""
    ink_width_m: FloatArray
    """(K,) width in [m] of the ink laid at that tick (0 without contact)."""
    base_m_enu: FloatArray | None = None
    """(K, 3) true vehicle base position in [m], ENU, where it differs from the writing point."""
    force_n: FloatArray | None = None
    """(K,) measured normal contact force in [N], for kinds that control force."""
    extra: Mapping[str, NDArray[Any]] = field(default_factory=dict)
    """Kind-specific logs (thrusts, wheel slips...), each (K, ...), named with their units;
    floats but for flags (the live agent's ``pen_contact``, bool)."""
    abort_reason: str | None = None
    """Why the run ended early (a deviation abort), None when flown to its end."""


@dataclass(frozen=True)
class WritingScore:
    """How well a job was written."""

    rmse_pen_down_m: float | None
    """RMSE in [m] of the writing point against its reference while the pen is down; None when
    the pen never came down (not measured)."""
    rmse_m: float
    """RMSE in [m] over the whole run."""
    max_error_m: float
    """Largest error in [m]."""
    iou: float | None
    """Intersection over union of written and target ink rasters, the target being the whole
    plan however much of it was flown (None: not measurable)."""
    extra: Mapping[str, float] = field(default_factory=dict)
    """Kind-specific figures, names with units (``force_rmse_n``, ``rmse_base_m``, ...): only
    those measured (none of the pen-down part of a flight whose pen never came down)."""
    error_m: FloatArray | None = None
    """(K,) the error in [m] at each tick of the flight whose pen-down RMS is
    ``rmse_pen_down_m``, where the kind measures it tick by tick (the brush quadrotor: what
    the agent's pace learns from, ``vehicle_agent/pace.py``); None otherwise."""


@dataclass(frozen=True)
class JobPhases:
    """How the live agent brings a kind from its home to the start of a job and back.

    An airborne kind takes off straight up at home to its cruise height, flies to the plan's
    first point (the brush quadrotor above its board; the hexarotor in front of its wall, at
    the standoff of its free-flight waypoints, from where the plan itself makes contact with the
    planned force and leaves it), and comes back to land. A ground kind rests on the floor: its
    take-off and landing end at once (motors on or off where it stands) and it drives to the
    plan's first point with the pen up, along ``route``."""

    airborne: bool
    """Takes off and lands vertically at home; False: rests and drives on the floor."""
    cruise: Literal["above_surface", "above_area", "floor"]
    """Height of pen-up flight: ``above_surface``, the surface plus the show's write height and
    clearance (a board seen from above); ``above_area``, the top of the writing area plus the
    show's clearance (a wall); ``floor``, the higher of home and the floor area (driving)."""
    transit_v_max_mps: float | None = None
    """Speed limit in [m/s] of the pen-up moves; None: the show's limits for the vehicle."""
    transit_a_max_mps2: float | None = None
    """Acceleration limit in [m/s^2] of the pen-up moves; None: the show's limits."""
    route: Literal["straight", "sideways_first"] = "straight"
    """``straight`` lines; ``sideways_first``: along world y first, then along world x, so that
    steps (edges across x) are met head on."""
    transit_wait_m: float | None = None
    """The pen-up reference waits while the vehicle is farther than this in [m] (horizontally)
    behind it (a climb holds a ground vehicle against the step's face for seconds); None: the
    reference runs on its clock."""


@dataclass(frozen=True)
class LiveReference:
    """What a live simulated vehicle tracks for one tick (the agent's setpoint)."""

    position_m_enu: Vec3
    """Reference of the vehicle reference point in [m], ENU."""
    velocity_mps_enu: Vec3 = (0.0, 0.0, 0.0)
    """Feed-forward velocity in [m/s], ENU."""
    acceleration_mps2_enu: Vec3 = (0.0, 0.0, 0.0)
    """Feed-forward acceleration in [m/s^2], ENU."""
    pen_down: bool = False
    """The pen is meant to touch."""
    force_n: float | None = None
    """Wanted normal contact force in [N], for kinds that control force."""


@dataclass(frozen=True)
class LiveState:
    """A live simulated vehicle after a tick (true values)."""

    position_m_enu: Vec3
    """Vehicle reference point in [m], ENU."""
    velocity_mps_enu: Vec3
    """Velocity in [m/s], ENU."""
    pen_tip_m_enu: Vec3
    """Where the pen tip is in [m], ENU."""
    pen_contact: bool
    """The pen touches its surface (anywhere on its plane; the agent knows the board's edges)."""
    pen_width_m: float
    """Width in [m] of the ink laid now (0 without contact)."""
    force_n: float | None = None
    """Measured normal contact force in [N], for kinds that sense it."""
    attitude_xyzw_enu: tuple[float, float, float, float] | None = None
    """The body's attitude: unit quaternion (x, y, z, w) turning body FLU into world ENU
    (``vehicles.attitude``); None: the room does not say."""


class LiveStateView(Protocol):
    """What the agent reads of a live vehicle after a tick: :class:`LiveState`'s fields, read
    only (a room may return its own frozen dataclass with these fields)."""

    @property
    def position_m_enu(self) -> Vec3: ...

    @property
    def velocity_mps_enu(self) -> Vec3: ...

    @property
    def pen_tip_m_enu(self) -> Vec3: ...

    @property
    def pen_contact(self) -> bool: ...

    @property
    def pen_width_m(self) -> float: ...

    @property
    def force_n(self) -> float | None: ...

    @property
    def attitude_xyzw_enu(self) -> tuple[float, float, float, float] | None: ...


@dataclass(frozen=True)
class PenReading:
    """The pen of an autopilot-flown vehicle at one instant, modelled from its pose."""

    tip_m_enu: Vec3
    """Where the pen tip is in [m], ENU."""
    width_m: float
    """Width in [m] of the ink it lays now (0 without contact)."""
    contact: bool
    """The pen touches its surface (anywhere on its plane; the agent knows the board's edges)."""


class AutopilotPen(Protocol):
    """The pen a vehicle flown behind an autopilot carries, which nothing senses: modelled from
    the vehicle's pose alone, as its kind's simulated world models it, so that the agent can
    measure ink and the writing point's error of a vehicle it only hears over MAVLink."""

    def read(self, position_m_enu: Vec3, rotation_body_to_enu: Mat3) -> PenReading:
        """The pen of a vehicle whose reference point is at ``position_m_enu`` in [m] and whose
        body (forward-left-up) is turned into the world (ENU) by ``rotation_body_to_enu``."""
        ...


@dataclass(frozen=True)
class AutopilotWorld:
    """What the agent's MAVLink backend takes from a kind's simulated world for a vehicle of the
    kind flown behind an autopilot."""

    pen: AutopilotPen
    """Its pen, modelled from its pose (contact over the whole surface plane)."""
    mocap_latency_s: float
    """Age in [s] of a motion-capture frame simulated from the true pose (a simulated vehicle)."""
    mocap_noise_std_m: float
    """Standard deviation in [m] per axis of the noise of such a frame."""


class SimulatedVehicle(Protocol):
    """A live simulated vehicle in flight (or driving), one control period per ``step``: the
    kind's world and controller in one closed loop. The agent's ``sim`` backend wraps it with an
    autopilot-like mode logic (take-off, hold, landing) and creates one per flight."""

    dt_s: float
    """Length of one tick in [s]."""

    def step(self, reference: LiveReference) -> None:
        """Advance one tick tracking ``reference``."""
        ...

    def state(self) -> LiveStateView:
        """The vehicle now."""
        ...


class SimulatedFleet(Protocol):
    """Live simulated vehicles of one kind and settings stepped together (a fleet host's
    vehicles in flight): a vehicle's own ``step`` only records its reference, and
    :meth:`step` flies every vehicle so given one, in one call. Each flies exactly as it would
    alone (same seed, same numbers)."""

    dt_s: float
    """Length of one tick in [s]."""

    def vehicle(self, start_m_enu: Vec3, *, seed: int) -> SimulatedVehicle:
        """A vehicle at rest at ``start_m_enu`` joins the fleet."""
        ...

    def release(self, vehicle: object) -> None:
        """``vehicle`` leaves the fleet (landed, stopped); an unknown one is ignored."""
        ...

    def step(self) -> None:
        """Advance every vehicle given a reference since the last step by one tick."""
        ...


class VehicleKind(Protocol):
    """One vehicle kind (one room). Implementations: ``vehicles.<room>.KIND``."""

    name: str
    """The kind's name in show files, e.g. ``quadrotor-brush``."""
    orientation: Orientation
    """The surface it writes on."""

    def settings(self, show: Show | None, vehicle_id: str | None) -> Any:
        """The kind's typed settings of vehicle ``vehicle_id`` in ``show`` (its limits, the
        show's planning and controller sections, its board); with ``show`` None, those of a show
        file that leaves every section at its default (what ``plan`` and ``fly`` use)."""
        ...

    def plan(self, strokes: Sequence[StrokeInput], surface: Surface, settings: Any) -> WritingPlan:
        """Plan writing ``strokes`` on ``surface`` (raises ``planner.errors.PlannerError`` naming
        the stroke and limit when it cannot)."""
        ...

    def command_reference(self, plan: WritingPlan, settings: Any) -> TrajectorySamples:
        """What the vehicle's position loop is given to track so that its writing point follows
        ``plan`` (the brush quadrotor: its body, placed so the tip is on the plan; a kind whose
        writing point is its reference point returns ``plan.samples``)."""
        ...

    def fly(self, plan: WritingPlan, settings: Any, *, seed: int = 0) -> FlownWriting:
        """Fly or drive ``plan`` in the kind's simulated world to its end, in a batch."""
        ...

    def score(self, plan: WritingPlan, flown: FlownWriting, settings: Any) -> WritingScore:
        """Metrics of a flown job against its plan."""
        ...

    def report(self, plan: WritingPlan, flown: FlownWriting, settings: Any, title: str) -> Any:
        """A matplotlib figure of the job (drawn only where a report is written)."""
        ...

    def simulated_vehicle(
        self, start_m_enu: Vec3, settings: Any, *, seed: int = 0
    ) -> SimulatedVehicle:
        """A live simulated vehicle at rest at ``start_m_enu`` for the agent's ``sim`` backend
        (which makes one per flight)."""
        ...

    def simulated_fleet(self, settings: Any) -> SimulatedFleet | None:
        """Live simulated vehicles stepped together, for a fleet host (a kind whose vehicles
        cost too much ticked one by one); None: each vehicle is stepped alone."""
        ...

    def phases(self, settings: Any) -> JobPhases:
        """How the live agent moves this kind between its home and its writing."""
        ...

    def width_range_m(self, settings: Any) -> tuple[float, float] | None:
        """The narrowest and widest line in [m] the kind draws with ``settings`` (a kiosk lets
        visitors draw widths within it), or None where it draws one width."""
        ...

    def autopilot_world(self, settings: Any) -> AutopilotWorld | None:
        """What a vehicle of this kind flown behind an autopilot (the MAVLink backend) takes from
        its simulated world: its pen modelled from its pose, and the motion capture (the brush
        quadrotor: its brush over the board's height); None: the kind flies in the sim only."""
        ...

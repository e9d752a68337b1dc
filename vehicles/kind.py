"""The one small interface through which the agent, the orchestrator, the kiosk preview and the CLI
reach a vehicle kind. Everything that differs between kinds lives in the kind's own room
(``vehicles/<kind>/``) behind a :class:`VehicleKind`; adding a kind means adding a room.

A job flows through a kind the same way for every kind::

    glyph (planner.glyphs) -> laid out on the surface (strokes in surface metres)
        -> VehicleKind.plan(...)            -> WritingPlan   (reference + feasibility)
        -> VehicleKind.fly(...) (batch) or the live agent ticking VehicleKind.simulated_vehicle(...)
        -> VehicleKind.score(...)           -> WritingScore  (RMSE, IoU, kind-specific figures)
        -> VehicleKind.report(...)          -> report.png

Pure: no transport, no asyncio, no show-file parsing here (rooms get typed settings).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from planner.samples import TrajectorySamples
from vehicles.surface import Orientation, Surface, Vec3

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


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
    extra: Mapping[str, FloatArray] = field(default_factory=dict)
    """Kind-specific logs (thrusts, wheel slips...), each (K, ...)."""
    abort_reason: str | None = None
    """Why the run ended early (a deviation abort), None when flown to its end."""


@dataclass(frozen=True)
class WritingScore:
    """How well a job was written."""

    rmse_pen_down_m: float
    """RMSE in [m] of the writing point against its reference while the pen is down."""
    rmse_m: float
    """RMSE in [m] over the whole run."""
    max_error_m: float
    """Largest error in [m]."""
    iou: float | None
    """Intersection over union of written and target ink rasters (None: not measurable)."""
    extra: Mapping[str, float] = field(default_factory=dict)
    """Kind-specific figures, names with units (``force_rmse_n``, ``rmse_base_m``, ...)."""


class SimulatedVehicle(Protocol):
    """A simulated vehicle stepped one control period per ``tick`` (the agent's sim backend wraps
    it; see ``vehicle_agent/backends/base.py`` ``SynchronousVehicle``)."""

    dt_s: float
    """Length of one tick in [s]."""


class VehicleKind(Protocol):
    """One vehicle kind (one room). Implementations: ``vehicles.<room>.KIND``."""

    name: str
    """The kind's name in show files, e.g. ``quadrotor-brush``."""
    orientation: Orientation
    """The surface it writes on."""

    def plan(self, strokes: Sequence[StrokeInput], surface: Surface, settings: Any) -> WritingPlan:
        """Plan writing ``strokes`` on ``surface`` (raises ``planner.errors.PlannerError`` naming
        the stroke and limit when it cannot)."""
        ...

    def fly(self, plan: WritingPlan, settings: Any, *, seed: int = 0) -> FlownWriting:
        """Fly or drive ``plan`` in the kind's simulated world to its end, in a batch."""
        ...

    def score(self, plan: WritingPlan, flown: FlownWriting) -> WritingScore:
        """Metrics of a flown job against its plan."""
        ...

    def report(
        self, plan: WritingPlan, flown: FlownWriting, score: WritingScore, title: str
    ) -> Any:
        """A matplotlib figure of the job (drawn only where a report is written)."""
        ...

    def simulated_vehicle(self, home_m_enu: Vec3, settings: Any, *, seed: int = 0) -> Any:
        """A live simulated vehicle for the agent's ``sim`` backend."""
        ...

"""Options of the Airshow planner (:func:`planner.pipeline.plan_strokes`), validated once."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from planner import defaults
from planner.board import BoardFrame
from planner.errors import PlannerError
from planner.limits import VehicleLimits
from planner.waypoints import PathSettings

if TYPE_CHECKING:  # the QP module is imported only where a job is planned
    from planner.qp_structure import QpLimits

PACES = ("limits", "nominal")
"""How fast a free total time flies (see ``PlanOptions.pace``)."""


def _default_board() -> BoardFrame:
    return BoardFrame(center_m_enu=(0.0, 0.0, 0.0))


@dataclass(frozen=True)
class PlanOptions:
    """Everything ``plan_strokes`` needs besides the strokes. SI units."""

    limits: VehicleLimits = field(default_factory=VehicleLimits)
    """Vehicle limits (acceleration per axis, speed, thrust, body rate)."""
    board: BoardFrame = field(default_factory=_default_board)
    """Board the strokes are written on (strokes are board-local, metres)."""
    write_height_m: float = defaults.WRITE_HEIGHT_M
    """Vehicle reference height above the board surface while the brush writes, [m]."""
    clearance_m: float = defaults.CLEARANCE_M
    """Extra height with the pen up, [m] (0: the brush never lifts between strokes)."""
    total_time_s: float | None = None
    """Fixed total duration in [s]; ``None`` lets the planner choose it (see ``pace``)."""
    pace: str = "limits"
    """With a free total time: ``"limits"`` flies every part of the path as fast as its binding
    limit allows (planner.timing); ``"nominal"`` starts from each leg's rest-to-rest time at
    0.6 v_max and half the smallest acceleration limit, stretched only where the fit breaks a
    limit, with the time penalty balanced there (the default before issue 15: 1.5-2x longer
    flights)."""
    time_law: bool = True
    """At pace ``"limits"`` with a free total time: fly the fitted path on the fastest smooth time
    law and fit the flight again in time (planner.time_law), 2.5-11 % shorter (median 6.8 % on
    220 characters); False flies the fit's own timing (the planner before issue 35's time
    law)."""
    split_threshold_m: float = defaults.SPLIT_THRESHOLD_M
    """Split-and-merge threshold, [m]."""
    resegment: bool = True
    """Run the optimal time re-segmentation."""
    resegment_method: str = "analytic"
    """``"analytic"`` (envelope gradient, L-BFGS) or ``"numerical"`` (the paper's eq. 56)."""
    solver: str = "piqp"
    """QP solver: ``"piqp"`` (default), ``"clarabel"`` or ``"osqp"``."""
    dense_qp_budget_s: float = 0.0
    """Predicted time [s] one plan may spend solving QPs on PIQP's dense interface, which needs
    no SciPy, before it turns to the sparse one (planner.fit_qp). 0, the default, always solves
    sparse: right for a process that plans more than once, since a dense solve is 2 to 180
    times slower (from one axis's QP of a short character to a coupled QP of the longest); a
    process that plans once sets about the cost of importing ``scipy.sparse``
    (``defaults.ONE_OFF_DENSE_QP_BUDGET_S``, as ``skyquill plan`` does)."""
    method: str = "qp"
    """``"qp"`` (limits imposed) or ``"closed-form"`` (limits only checked)."""
    sample_rate_hz: float = defaults.SAMPLE_RATE_HZ
    """Rate of ``TRAJ.json`` samples, [Hz] (>= 100)."""
    knot_spacing_s: float = 0.2
    """Time between spline knots, [s]."""
    jerk_weight_s5: float = 1e-4
    """``w_g`` of eq. (32) in [s^5]."""
    densify_spacing_m: float = 0.05
    """Largest spacing of data points along straight pieces, [m]."""
    time_penalty: float | None = None
    """``rho`` of the free-time cost per second (pace ``"nominal"``); ``None``: balanced at the
    initial times."""
    min_segment_time_s: float = 0.05
    """Shortest time re-segmentation may give between two data points, [s]."""
    pen_contact_tolerance_m: float = 0.005
    """Pen counts as down within this height above writing height, [m]."""
    fit_tolerance_m: float | None = 0.025
    """Largest allowed distance of the written path from the strokes (at turning points and
    along the pen-down path), [m]; where the fit strays further it is tightened locally and
    solved again (planner.refine), and only then is the plan refused -- otherwise the limits
    would be met silently by writing a different shape. ``None`` disables the check."""

    def __post_init__(self) -> None:
        if self.solver not in defaults.SOLVERS:
            known = defaults.SOLVERS
            raise PlannerError(f"unknown solver {self.solver!r}; one of {known}", field="solver")
        if self.method not in ("qp", "closed-form"):
            raise PlannerError(f"unknown method {self.method!r}", field="method")
        if self.pace not in PACES:
            raise PlannerError(f"unknown pace {self.pace!r}; one of {PACES}", field="pace")
        if self.resegment_method not in ("analytic", "numerical"):
            raise PlannerError(f"unknown method {self.resegment_method!r}", field="resegment")
        if self.sample_rate_hz < 100.0:
            raise PlannerError("must be >= 100 Hz", field="sample_rate_hz")
        if self.total_time_s is not None and not self.total_time_s > 0.0:
            raise PlannerError("must be > 0 s", field="total_time_s")
        for name in ("write_height_m", "knot_spacing_s", "jerk_weight_s5", "densify_spacing_m"):
            if not getattr(self, name) > 0.0:
                raise PlannerError(f"must be > 0, got {getattr(self, name)}", field=name)
        if not self.dense_qp_budget_s >= 0.0:
            raise PlannerError(
                f"must be >= 0, got {self.dense_qp_budget_s}", field="dense_qp_budget_s"
            )
        if not self.clearance_m >= 0.0:
            raise PlannerError(f"must be >= 0, got {self.clearance_m}", field="clearance_m")

    def path_settings(self) -> PathSettings:
        """Geometry and initial timing of the data path."""
        return PathSettings(
            write_height_m=self.write_height_m,
            clearance_m=self.clearance_m,
            split_threshold_m=self.split_threshold_m,
            densify_spacing_m=self.densify_spacing_m,
            nominal_speed_mps=0.6 * self.limits.v_max_mps,
            nominal_accel_mps2=0.5 * min(self.limits.a_max_mps2),
        )

    def qp_limits(self, write_z_m: float) -> QpLimits:
        """Linear QP limits: acceleration bounds (eq. 13), speed, z never below writing height."""
        from planner.qp_structure import QpLimits

        lower, upper = self.limits.accel_bounds_mps2()
        return QpLimits(lower, upper, self.limits.v_max_mps, z_floor_m=write_z_m)

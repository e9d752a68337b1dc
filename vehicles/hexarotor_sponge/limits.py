"""The wall planner's limits and cost weights (paper eq. 7a, 7c, 7g, and our additions to them),
in a module of their own below every planner module that reads them (``nlp``, ``steps``,
``diagnosis``, ``long_periods``, ``plan``): the shared type lives below its users, so they
import no ring (held by the import-linter contract on ``vehicles.hexarotor_sponge``)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from planner.errors import PlannerError
from vehicles.hexarotor_sponge import defaults


@dataclass(frozen=True)
class Limits:
    """Planner limits and weights (paper's defaults)."""

    v_max_mps: float = defaults.V_MAX_MPS
    """Largest speed of the writing point in [m/s]."""
    a_max_mps2: float = defaults.A_MAX_MPS2
    """Largest acceleration in [m/s^2]."""
    force_rate_max_nps: float = defaults.FORCE_RATE_MAX_NPS
    """Largest |dF/dt| in [N/s]."""
    h_init_s: float = 0.15
    """Time step in [s] the steps are allocated at and IPOPT starts from (paper: 0.1 s; its
    bound ``h_max_s`` allows 0.2 s). 0.15 s plans letters A, I, R and three Chinese characters
    with a third fewer steps and IPOPT iterations than 0.1 s, their durations within 0.6 %;
    0.2 s leaves no slack under ``h_max_s`` and a stroke's force ramp is found infeasible."""
    h_max_s: float = 0.2
    """Upper bound of a time step in [s] (eq. 7c)."""
    weight_v: float = 1.0
    """Cost weight of |v|^2 in [1/(m/s)^2 s] (eq. 7a)."""
    weight_u: float = 1e-3
    """Cost weight of the control force's change from hover, per [N^2 s]."""
    weight_du: float = 1e-2
    """Cost weight of the control force's change between steps, per [N^2 s]."""
    time_weight: float = 1.0
    """gamma: cost per second of writing (eq. 7a)."""
    weight_force: float = 20.0
    """Cost weight per [N^2 s] of the force's departure from the waypoint forces interpolated
    along the stroke (an addition to eq. 7a: the wanted width holds between waypoints too)."""
    weight_dh: float = 10.0
    """Cost weight per [s^2] of a time step's change from the step before (an addition to eq. 7a).
    Without it, moving time between neighbouring steps barely changes the cost, and IPOPT spends
    most of its iterations at the last barrier creeping along those flat, indefinite directions
    (the Hessian regularised at nearly every iteration, neighbouring steps 0.02 and 0.19 s). 10
    takes the six bench glyphs from 1148 iterations to 618 (0.75 -> 0.38 s CPU per letter,
    median, solvers built), their durations within 0.3 % and steps within 0.03 s of their
    neighbours."""
    corridor_m: float | None = 0.5e-3
    """Half width in [m] of the corridor around the stroke's parabola between two waypoints of
    a contact period that its nodes are held in (``corridor``: our extension of eq. 7, which
    pins positions at the waypoints only); None: the paper's eq. 7. The parabolas lie within
    1 mm of the stroke (``parabolas.FIT_TOLERANCE_M``), so the nodes lie within 1.5 mm; the
    pen rides the corridor's inner edge on curves, and a line 10 mm wide laid 2 mm off its
    target has an IoU of 0.67, so the corridor is narrow: 2 mm around chords gave the 1 m "8"
    a plan IoU of 0.79, 0.5 mm around parabolas 0.95."""

    def __post_init__(self) -> None:
        names = ["v_max_mps", "a_max_mps2", "force_rate_max_nps", "h_init_s", "h_max_s"]
        for name in names + ([] if self.corridor_m is None else ["corridor_m"]):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise PlannerError(
                    f"planner limit {name} must be positive, not {value}", field=name
                )

"""The position controller's settings (:class:`ControllerConfig`) and its two presets, apart from
the controller (:mod:`vehicles.quadrotor_brush.control.controller`): the kind's settings, which
every plan reads, hold a controller's settings, and a plan then loads no control law."""

from __future__ import annotations

from dataclasses import dataclass, field

from vehicles.quadrotor_brush.control.errors import ControlError
from vehicles.quadrotor_brush.control.estimator import EstimatorConfig
from vehicles.quadrotor_brush.control.inner import G_C
from vehicles.quadrotor_brush.control.rpt import DEFAULT_GAINS, PAPER_GAINS, RptGains


@dataclass(frozen=True)
class ControllerConfig:
    """Everything the position controller needs besides the number of vehicles."""

    gains: RptGains = DEFAULT_GAINS
    """RPT design per axis."""
    disturbance_compensation: bool = True
    """Subtract the estimated external acceleration from the command and add the known drag of
    the reference velocity (``estimator.drag_per_s``)."""
    brush_lever_m: float = 0.335
    """Reference point to brush tip at nominal press in [m]; 0 aims the body, not the tip."""
    lever_filter_bandwidth_radps: float | None = None
    """Pole of the first-order low-pass on the disturbance used for the tip shift in [rad/s];
    ``None``: the stable pole of the tip inverse (about 5.6 rad/s)."""
    feedforward_lead_s: tuple[float, float, float] = (0.061, 0.061, 0.025)
    """First-order lead of the acceleration feed-forward per axis in [s]: the inner loop's
    2 zeta / w_n (x, y) or motor lag (z), plus half a tick of hold."""
    feedforward_second_order_s2: tuple[float, float, float] = (0.0016, 0.0016, 0.0)
    """Second-order lead per axis in [s^2]: 1 / w_n^2 of the inner attitude loop."""
    integral_limit_mps2: float = 2.0
    """Clamp on the integral term's contribution per axis in [m/s^2]."""
    estimator: EstimatorConfig = field(default_factory=EstimatorConfig)
    """Mocap filter."""
    gravity_mps2: float = 9.81
    """Gravity used by the conversion in [m/s^2]."""
    max_tilt_rad: float = 0.5
    """Roll and pitch command limit in [rad]."""
    max_throttle: float = 2.0 * 9.81 * float(G_C[0, 2])
    """Throttle limit (thrust-to-weight 2 at the G_c throttle gain)."""

    def __post_init__(self) -> None:
        if self.brush_lever_m < 0.0:
            raise ControlError("must be non-negative", field="brush_lever_m")
        if not self.integral_limit_mps2 > 0.0:
            raise ControlError("must be positive", field="integral_limit_mps2")
        bandwidth = self.lever_filter_bandwidth_radps
        if bandwidth is not None and not 0.0 < bandwidth < 20.0:
            raise ControlError("must be in (0, 20)", field="lever_filter_bandwidth_radps")


PAPER_CONFIG = ControllerConfig(
    gains=PAPER_GAINS,
    disturbance_compensation=False,
    brush_lever_m=0.0,
    feedforward_lead_s=(0.0, 0.0, 0.0),
    feedforward_second_order_s2=(0.0, 0.0, 0.0),
    estimator=EstimatorConfig(drag_per_s=(0.0, 0.0, 0.0)),
)
"""The controller as published: RPT (eq. 8) with the error integral and the reference's
acceleration as feed-forward, aiming the body; the mocap filter knows no drag."""

DEFAULT_CONFIG = ControllerConfig()
"""The shipped controller: the paper's pole pattern at eps 0.6, disturbance cancellation with
known rotor drag, inner-loop lead on the feed-forward, brush-tip aiming."""

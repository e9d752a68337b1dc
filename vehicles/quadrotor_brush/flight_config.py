"""What a flight of the brush quadrotor is flown with (:class:`FlightConfig`), apart from the
closed loop (:mod:`vehicles.quadrotor_brush.flight`) so that the kind's settings, which every plan
reads, load no flight code."""

from __future__ import annotations

from dataclasses import dataclass, field

from vehicles.deviation import DeviationLimit
from vehicles.quadrotor_brush.control.config import DEFAULT_CONFIG, ControllerConfig
from vehicles.quadrotor_brush.params import WorldParams


@dataclass(frozen=True)
class FlightConfig:
    """World and controller of a flight."""

    world: WorldParams = field(default_factory=WorldParams)
    """The simulated world (vehicle, brush, wind, mocap, board, rates)."""
    controller: ControllerConfig = DEFAULT_CONFIG
    """The position controller."""
    settle_s: float = 1.0
    """Extra flight after the longest reference ends, in [s]."""
    preroll_s: float = 3.0
    """Hover on the first reference sample before clock zero, in [s], not recorded: the vehicle
    meets the job already settled in the wind (the filter has learnt it, the body leans into
    it), as a vehicle that took off and flew to the start would."""
    deviation: DeviationLimit | None = None
    """End the flight when a vehicle's tracking error stays above this bound (None: never)."""

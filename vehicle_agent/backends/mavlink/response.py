"""What the backend learns of one vehicle in flight: its true state (SITL) and its lag.

:class:`ResponseAid` bundles the simulator's truth (:mod:`~vehicle_agent.backends.mavlink.truth`,
when the settings ask for it) and the identified response delay of the autopilot's position loop
(:mod:`~vehicle_agent.backends.mavlink.lag`), and leads the plan's setpoints by that delay.
"""

from __future__ import annotations

import logging
from typing import Any

from vehicle_agent.backends.base import Setpoint, Vec3
from vehicle_agent.backends.mavlink.lag import ResponseDelayEstimator, lead_setpoint, plan_jerk
from vehicle_agent.backends.mavlink.mocap import MocapSource
from vehicle_agent.backends.mavlink.settings import MavlinkSettings
from vehicle_agent.backends.mavlink.truth import (
    TRUTH_MESSAGES,
    TruthSample,
    truth_mocap,
)
from vehicle_agent.backends.mavlink.truth_filter import SmoothedTruthTracker, simulator_time_s
from vehicles.kind import PenReading

log = logging.getLogger(__name__)


class ResponseAid:
    """Truth and lag of one vehicle; leads its setpoints."""

    def __init__(self, settings: MavlinkSettings, *, seed: int = 0) -> None:
        self.settings = settings
        self.truth: SmoothedTruthTracker | None = None
        """The simulator's state, smoothed of its centimetre steps (None: not asked for)."""
        if settings.truth == "sitl":
            self.truth = SmoothedTruthTracker(settings.origin_m_enu)
        self.lag = ResponseDelayEstimator()
        self._seed = seed
        self._logged_lead = -1.0
        self._previous: tuple[float, Setpoint] | None = None
        """The last plan setpoint led and its time [s], for the plan's jerk."""

    @property
    def lead_s(self) -> float:
        """The lead in [s] applied to position setpoints now."""
        if self.settings.lead_s is not None:
            return self.settings.lead_s
        return self.lag.delay_s or 0.0

    def mocap_source(self) -> MocapSource | None:
        """The truth as a mocap source (the show's latency and noise); None without truth."""
        if self.truth is None:
            return None
        s = self.settings
        return truth_mocap(self.truth, s.mocap_latency_s, s.mocap_noise_std_m, self._seed)

    def truth_message(self, flavor: str) -> int | None:
        """The message id to ask the autopilot for (None: no truth wanted)."""
        return TRUTH_MESSAGES.get(flavor) if self.truth is not None else None

    def on_message(
        self, message: Any, now_s: float, *, resting_at_home: bool, autopilot_time_ms: int
    ) -> None:
        """A truth message arrived at agent time ``now_s`` [s]; ``autopilot_time_ms``: the
        autopilot's clock as its last ATTITUDE said (0: none yet)."""
        if self.truth is not None:
            simulator_s = simulator_time_s(autopilot_time_ms)
            self.truth.absorb(message, now_s, resting_at_home=resting_at_home,
                              simulator_s=simulator_s)  # fmt: skip

    def true_state(self, now_s: float) -> TruthSample | None:
        """The latest truth if it is fresh (younger than half a second)."""
        sample = None if self.truth is None else self.truth.latest
        if sample is None or now_s - sample.time_s > 0.5:
            return None
        return sample

    def lead(self, setpoint: Setpoint, now_s: float) -> Setpoint:
        """The plan's setpoint at agent time ``now_s`` [s] led by the autopilot's delay
        (position setpoints only), along the plan's jerk between consecutive setpoints."""
        lead_s = self.lead_s
        if abs(lead_s - self._logged_lead) >= 0.01:
            self._logged_lead = lead_s
            log.info("leading setpoints by %.3f s", lead_s)
        jerk = plan_jerk(self._previous, now_s, setpoint)
        self._previous = (now_s, setpoint)
        return lead_setpoint(setpoint, lead_s, jerk)

    def sent(self, now_s: float, position_m_enu: Vec3) -> None:
        self.lag.sent(now_s, position_m_enu)

    def measured(
        self,
        now_s: float,
        estimate_m_enu: Vec3,
        truth: TruthSample | None,
        reading: PenReading | None,
    ) -> None:
        """Where the pen writes, for the lag: the tip on the board as ``reading`` has it (the pen
        as :func:`~vehicle_agent.backends.mavlink.snapshot.pen_reading` read it this tick, for
        the snapshot too), else the body (no pen, or the brush in the air): on ``truth``, the
        caller's :meth:`true_state` this tick, when there is one (on PX4 1.16 SIH the
        autopilot's estimate trails it by 0.015-0.025 s, which a fit on the estimate added to
        the lead), else the estimate (``estimate_m_enu``, [m]).

        The tip on the board: a vehicle writing at a steady speed leans into its drag, and the
        brush pressed 0.3 m below trails its body. On ArduCopter 4.7 SITL (Airshow show, quiet,
        12 jobs) the tip's mean along the stroke was 1.2-4.7 mm behind the plan with the lead
        fitted on the body, 0.3-2.7 mm with it fitted on the tip (IoU median 0.75 -> 0.76,
        worst 0.71 -> 0.74). The body in the air: a transit's acceleration swings the hanging
        brush by centimetres, which is no delay; fitted on it, mavsim's stiff loop was led by
        0.048 s and 一 went from 2.6 to 13.7 mm (tests/test_mavlink_e2e.py)."""
        body = estimate_m_enu if truth is None else truth.position_m_enu
        point = reading.tip_m_enu if reading is not None and reading.contact else body
        self.lag.measured(now_s, point)

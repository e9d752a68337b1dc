"""Is the autopilot still ours to fly? Decided each tick from what it said (pure, time injected).

A fault, never a fight: a lost heartbeat, a mode or arming change we did not command (the pilot's
switch or the autopilot's own failsafe), a STATUSTEXT naming a failsafe, a gap in our setpoint
stream longer than the autopilot's timeout, or a take-off/landing that does not end in time.
Not a fault: the autopilot disarming on the ground after a landing we commanded, whatever mode it
reports with that disarm (PX4 goes back to the mode the pilot last chose, e.g. OFFBOARD). Nor is
one heartbeat in another mode than ours: a mode change counts once two heartbeats in a row say it
(the first heartbeat after our command can predate its effect, and PX4 says the mode it goes back
to one heartbeat before the disarm that comes with it: a vehicle faulted after a finished job,
"mode changed to OFFBOARD ... not streaming", issue 31). A real change costs one heartbeat more
to see (1 s at both autopilots' rate).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from vehicle_agent.backends.base import BackendMode
from vehicle_agent.backends.mavlink.state import MAV_LANDED_STATE_ON_GROUND as ON_GROUND
from vehicle_agent.backends.mavlink.state import SEVERITY_WARNING, Flavor, LinkState

FLYING_MODES = ("takeoff", "hold", "offboard", "landing")


@dataclass(frozen=True)
class WatchLimits:
    """Timeouts of one vehicle, all in [s] of agent time."""

    heartbeat_timeout_s: float
    """No autopilot heartbeat for this long: lost link."""
    setpoint_timeout_s: float
    """Our setpoint stream may pause this long before the autopilot stops following it."""
    takeoff_timeout_s: float
    """A take-off must be complete within this long."""
    land_timeout_s: float
    """A landing must end (disarmed on the ground) within this long."""


@dataclass(frozen=True)
class Commanded:
    """What we last asked of the autopilot."""

    custom_mode: int | None
    """HEARTBEAT custom_mode of the last mode we set."""
    at_heartbeat: int
    """Heartbeat count when our last mode or arming change was accepted."""
    last_sent_s: float
    """Agent time in [s] of our last setpoint."""


class Watchdog:
    """Heartbeat bookkeeping and the per-tick verdict."""

    def __init__(self, limits: WatchLimits) -> None:
        self.limits = limits
        self._hb_count, self._hb_at_s = 0, math.nan
        self._last_tick_s = math.inf
        self.mode_since_s = math.nan
        """Agent time in [s] the backend's mode began (NaN: after the last tick)."""
        self._other_mode_at_hb: int | None = None
        """Heartbeat count at which the autopilot first said a mode other than ours (None: it
        says ours)."""

    def mode_changed(self) -> None:
        """Our backend mode just changed: its timeouts start at the next tick."""
        self.mode_since_s = math.nan

    def check(
        self,
        now_s: float,
        period_s: float,
        state: LinkState,
        flavor: Flavor,
        mode: BackendMode,
        commanded: Commanded,
    ) -> str | None:
        """Why the vehicle is not ours any more (the first reason), or None."""
        stalled_s = now_s - self._last_tick_s - period_s
        if stalled_s > 2 * period_s:
            # The agent did not run (its clock jumped ahead): we did not listen either, and what
            # the vehicle said meanwhile is still in the socket. Only count time we listened.
            self._hb_at_s += stalled_s
        self._last_tick_s = now_s
        if state.heartbeats != self._hb_count or math.isnan(self._hb_at_s):
            self._hb_count, self._hb_at_s = state.heartbeats, now_s
        if math.isnan(self.mode_since_s):
            self.mode_since_s = now_s
        for check in (self._link, self._texts, self._control, self._progress):
            reason = check(now_s, state, flavor, mode, commanded)
            if reason is not None:
                return reason
        return None

    def link_silent_s(self, now_s: float) -> float:
        """How long in [s] the autopilot has sent no heartbeat, as of the last tick."""
        return now_s - self._hb_at_s

    def _link(self, now_s: float, *_: object) -> str | None:
        silent_s = self.link_silent_s(now_s)
        if silent_s > self.limits.heartbeat_timeout_s:
            return f"lost link: no heartbeat from the autopilot for {silent_s:.1f} s"
        return None

    def _texts(self, now_s: float, state: LinkState, flavor: Flavor, mode: BackendMode,
               commanded: Commanded) -> str | None:  # fmt: skip
        texts = state.take_texts()
        if mode not in FLYING_MODES:
            return None
        for severity, text in texts:
            if severity <= SEVERITY_WARNING and "failsafe" in text.lower():
                return f"autopilot failsafe: {text}"
        return None

    def _control(self, now_s: float, state: LinkState, flavor: Flavor, mode: BackendMode,
                 commanded: Commanded) -> str | None:  # fmt: skip
        fresh = state.heartbeats > commanded.at_heartbeat
        landed = mode == "landing" and not state.armed
        # a landing we commanded is over when it disarms, whatever mode comes with the disarm
        other = mode in FLYING_MODES and fresh and state.custom_mode != commanded.custom_mode
        if not other:
            self._other_mode_at_hb = None
        elif self._other_mode_at_hb is None:
            self._other_mode_at_hb = state.heartbeats
        if mode in FLYING_MODES and fresh and not landed:
            if other and self._other_mode_at_hb is not None:
                if state.heartbeats > self._other_mode_at_hb:  # said twice in a row
                    name = flavor.mode_name(state.custom_mode or 0)
                    return f"mode changed to {name} by the pilot or the autopilot: not streaming"
            elif not state.armed and mode == "takeoff" and state.landed_state == ON_GROUND:
                return (
                    "vehicle disarmed on the ground before it climbed (a take-off that did not"
                    " leave the ground: PX4's preflight disarm timeout, or the pilot)"
                )
            elif not state.armed:
                return "vehicle disarmed in flight by the pilot or the autopilot"
        gap_s = now_s - commanded.last_sent_s
        if mode in ("hold", "offboard") and gap_s > self.limits.setpoint_timeout_s:
            return (
                f"setpoint stream stopped for {gap_s:.1f} s (autopilot timeout "
                f"{self.limits.setpoint_timeout_s:.1f} s): its failsafe has stopped the vehicle"
            )
        return None

    def _progress(self, now_s: float, state: LinkState, flavor: Flavor, mode: BackendMode,
                  commanded: Commanded) -> str | None:  # fmt: skip
        in_mode_s = now_s - self.mode_since_s
        if mode == "takeoff" and in_mode_s > self.limits.takeoff_timeout_s:
            return f"take-off not complete after {in_mode_s:.0f} s"
        if mode == "landing" and in_mode_s > self.limits.land_timeout_s:
            return f"landing not complete after {in_mode_s:.0f} s"
        return None

"""The in-process simulated vehicle: the vehicle kind's live simulated vehicle (its world and
controller in one closed loop, ``VehicleKind.simulated_vehicle``) behind an autopilot-like mode
logic.

The backend plays the autopilot's part around the kind's vehicle: it rests on the ground until
``takeoff`` (the world is not stepped there: it has no ground), climbs and descends along its own
min-jerk moves, holds the last point when no setpoint comes, and freezes where it touched down.
A kind that is not airborne (``VehicleKind.phases``: a ground writer) has no height to gain or
lose: its take-off (motors on where it rests) and landing (motors off where it stands) end at
once. Time is the world's tick count; nothing reads a clock.

In a fleet host the live vehicles come from the kind's :class:`vehicles.kind.SimulatedFleet`
(``fleet``): a tick is then cut in two, :meth:`SimVehicle.begin_tick` (the reference given)
and :meth:`SimVehicle.end_tick` (the vehicle read back), and the fleet steps in between, once for
every vehicle of the host whose tick came in that turn of the event loop
(:class:`vehicle_agent.backends.sim_round.StepRound`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from sim.battery import BatteryState, Phase, discharge, full, minutes_left
from vehicle_agent.backends.base import (
    BackendError,
    BackendMode,
    Setpoint,
    SynchronousBackend,
    Vec3,
    VehicleSnapshot,
)
from vehicle_agent.backends.sim_round import StepRound
from vehicle_agent.motion import Move, plan_move
from vehicles import DEFAULT_KIND
from vehicles.batteries import kind_battery
from vehicles.kind import LiveReference, SimulatedFleet, SimulatedVehicle, VehicleKind
from vehicles.registry import vehicle_kind

TOUCHDOWN_TOLERANCE_M = 0.03
"""Height above the ground in [m] below which a finished descent counts as landed."""
SETTLE_LIMIT_S = 2.0
"""After a take-off or landing move ends, how long in [s] the vehicle may take to get there."""


class SimVehicle:
    """One simulated vehicle of a kind with an autopilot-like mode logic (synchronous, pure).

    ``kind`` and its ``settings`` (default: ``vehicles.DEFAULT_KIND`` with the defaults a show
    file has) make a new live vehicle per flight, seeded ``seed`` plus the flight's number."""

    def __init__(
        self,
        home_m_enu: Vec3,
        *,
        kind: VehicleKind | None = None,
        settings: Any = None,
        seed: int = 0,
        vertical_speed_mps: float = 0.5,
        vertical_accel_mps2: float = 0.8,
        contact_region: Callable[[Vec3], bool] | None = None,
        fleet: SimulatedFleet | None = None,
    ) -> None:
        self.kind = kind if kind is not None else vehicle_kind(DEFAULT_KIND)
        self.settings = settings if settings is not None else self.kind.settings(None, None)
        self.seed = seed
        self.home_m_enu = home_m_enu
        self.dt_s = self.kind.simulated_vehicle(home_m_enu, self.settings, seed=seed).dt_s
        self.airborne = self.kind.phases(self.settings).airborne
        """It climbs and descends (False: take-off and landing end at once)."""
        self.vertical_speed_mps = vertical_speed_mps
        self.vertical_accel_mps2 = vertical_accel_mps2
        self.contact_region = contact_region
        """Where the board is: contact only counts with the tip over it (None: everywhere)."""
        self.fleet = fleet
        """The fleet its live vehicles join in flight (None: a vehicle of its own each)."""
        self.t_s = 0.0
        self.mode: BackendMode = "idle"
        self._rest_m_enu: Vec3 = home_m_enu
        self._vehicle: SimulatedVehicle | None = None
        self._move: Move | None = None
        self._hold: Setpoint = Setpoint(position_m_enu=home_m_enu)
        self._flights = 0
        self.battery = kind_battery(self.kind.name)
        """Its kind's pack and draw per phase (``vehicles/<room>/battery.py``)."""
        self.battery_state: BatteryState = full(self.battery.pack)
        """Its pack now: drawn each tick at the power of what it does (:meth:`phase`)."""

    # --- mode commands -------------------------------------------------------------------------
    def takeoff(self, hover_m_enu: Vec3) -> None:
        """Spin up where it rests and climb straight up to the height of ``hover_m_enu``."""
        if self.mode != "idle":
            raise BackendError(f"cannot take off in mode {self.mode}")
        start, seed = self._rest_m_enu, self.seed + self._flights
        if self.fleet is not None:
            self._vehicle = self.fleet.vehicle(start, seed=seed)
        else:
            self._vehicle = self.kind.simulated_vehicle(start, self.settings, seed=seed)
        self._flights += 1
        if not self.airborne:
            self.mode, self._hold = "hold", Setpoint(position_m_enu=self._position())
            return
        self._begin_move(start, (start[0], start[1], hover_m_enu[2]), "takeoff")

    def land(self) -> None:
        """Descend straight down to ground height (the home's z)."""
        if self.mode in ("idle", "estop"):
            return
        if not self.airborne:
            self._rest_m_enu = self._position()
            self._drop_vehicle()
            self._move, self.mode = None, "idle"
            return
        here = self._hold.position_m_enu
        self._begin_move(here, (here[0], here[1], self.home_m_enu[2]), "landing")

    def estop(self) -> None:
        """Motors off: the vehicle drops to the ground where it is and stays there (a ground
        vehicle stops on the floor it stands on)."""
        x, y, z = self._position()
        self._rest_m_enu = (x, y, z if not self.airborne else self.home_m_enu[2])
        self._drop_vehicle()
        self.mode = "estop"

    def recover(self) -> None:
        """After ``estop``: the vehicle rests where it fell, ``idle``, ready to take off again."""
        if self.mode not in ("idle", "estop"):
            raise BackendError(f"cannot recover in mode {self.mode}: it is not at rest")
        self.mode = "idle"

    def swap_battery(self) -> None:
        """The crew put a fresh pack in: only into a vehicle at rest on the ground."""
        if self._vehicle is not None or self.mode not in ("idle", "estop"):
            raise BackendError(f"cannot swap the battery in mode {self.mode}: it is not at rest")
        self.battery_state = full(self.battery.pack)

    def close(self) -> None:
        """Leave the fleet, if in flight in one (the agent stops)."""
        self._drop_vehicle()

    def _drop_vehicle(self) -> None:
        if self.fleet is not None and self._vehicle is not None:
            self.fleet.release(self._vehicle)
        self._vehicle = None

    def _begin_move(self, start: Vec3, end: Vec3, mode: BackendMode) -> None:
        self._move = plan_move(
            start,
            end,
            self.t_s,
            v_max_mps=self.vertical_speed_mps,
            a_max_mps2=self.vertical_accel_mps2,
        )
        self.mode = mode

    # --- the tick ------------------------------------------------------------------------------
    def tick(self, setpoint: Setpoint | None) -> VehicleSnapshot:
        """One control period: the reference from the mode (or ``setpoint``), then the loop."""
        if self.begin_tick(setpoint) and self.fleet is not None:
            self.fleet.step()
        return self.end_tick()

    def begin_tick(self, setpoint: Setpoint | None) -> bool:
        """The first half of :meth:`tick`: the reference handed to the live vehicle. True when
        it is in flight in a fleet, to be stepped before :meth:`end_tick`."""
        if setpoint is not None:
            if self.mode not in ("hold", "offboard"):
                raise BackendError(f"setpoint refused in mode {self.mode}")
            self.mode, self._hold = "offboard", setpoint
        elif self.mode == "offboard":
            self.mode = "hold"
            self._hold = Setpoint(position_m_enu=self._hold.position_m_enu)
        reference = self._reference()
        if reference is None:
            return False
        self._step(reference)
        return self.fleet is not None

    def end_tick(self) -> VehicleSnapshot:
        """The second half of :meth:`tick`: time goes on, a finished move ends, the vehicle
        now."""
        self.t_s += self.dt_s
        power_w = self.battery.power_w.of(self.phase())
        self.battery_state = discharge(self.battery.pack, self.battery_state, power_w, self.dt_s)
        self._finish_move()
        return self.snapshot()

    def phase(self) -> Phase:
        """What it does now, as its battery sees it: at rest on the ground, holding (hovering,
        climbing, descending; a ground vehicle standing with its motors on), moving with the pen
        up, or writing."""
        if self._vehicle is None:
            return "rest"
        if self.mode != "offboard":
            return "hover"
        return "writing" if self._hold.pen_down else "transit"

    def _reference(self) -> Setpoint | None:
        if self._vehicle is None:
            return None
        if self.mode in ("takeoff", "landing") and self._move is not None:
            return self._move.setpoint(self.t_s)
        return self._hold

    def _step(self, reference: Setpoint) -> None:
        assert self._vehicle is not None
        self._vehicle.step(
            LiveReference(
                position_m_enu=reference.position_m_enu,
                velocity_mps_enu=reference.velocity_mps_enu,
                acceleration_mps2_enu=reference.acceleration_mps2_enu,
                pen_down=reference.pen_down,
                force_n=reference.force_n,
            )
        )

    def _finish_move(self) -> None:
        move = self._move
        if move is None or self.mode not in ("takeoff", "landing") or not move.done(self.t_s):
            return
        error = math.dist(self._position(), move.end_m_enu)
        late = self.t_s - move.end_s >= SETTLE_LIMIT_S
        if error > TOUCHDOWN_TOLERANCE_M and not late:
            self._hold = Setpoint(position_m_enu=move.end_m_enu)
            return
        self._move = None
        if self.mode == "takeoff":
            self.mode, self._hold = "hold", Setpoint(position_m_enu=move.end_m_enu)
        else:
            x, y, _ = self._position()
            self._rest_m_enu = (x, y, self.home_m_enu[2])
            self._drop_vehicle()
            self.mode = "idle"

    # --- state ---------------------------------------------------------------------------------
    def _position(self) -> Vec3:
        if self._vehicle is None:
            return self._rest_m_enu
        return self._vehicle.state().position_m_enu

    def snapshot(self) -> VehicleSnapshot:
        """The vehicle now."""
        fraction, voltage_v, minutes = self._battery_now()
        if self._vehicle is None:
            return VehicleSnapshot(
                t_s=self.t_s,
                position_m_enu=self._rest_m_enu,
                velocity_mps_enu=(0.0, 0.0, 0.0),
                armed=False,
                mode=self.mode,
                on_ground=True,
                pen_contact=False,
                pen_width_m=0.0,
                battery_fraction=fraction,
                battery_voltage_v=voltage_v,
                battery_minutes_left=minutes,
            )
        state = self._vehicle.state()
        tip, contact = state.pen_tip_m_enu, state.pen_contact
        if contact and self.contact_region is not None and not self.contact_region(tip):
            contact = False  # the world's surface spans everything; the real board does not
        return VehicleSnapshot(
            t_s=self.t_s,
            position_m_enu=state.position_m_enu,
            velocity_mps_enu=state.velocity_mps_enu,
            armed=True,
            mode=self.mode,
            on_ground=False,
            pen_contact=contact,
            pen_tip_m_enu=tip,
            pen_width_m=state.pen_width_m if contact else 0.0,
            force_n=state.force_n,
            attitude_xyzw_enu=state.attitude_xyzw_enu,
            battery_fraction=fraction,
            battery_voltage_v=voltage_v,
            battery_minutes_left=minutes,
        )

    def _battery_now(self) -> tuple[float, float, float]:
        """Its battery: charge left (0..1), terminal voltage [V], minutes left at its cruise
        draw [min]."""
        state, battery = self.battery_state, self.battery
        cruise_w = battery.power_w.of(battery.cruise)
        minutes = minutes_left(battery.pack, state.charge_fraction, cruise_w)
        return state.charge_fraction, state.voltage_v, minutes


class SimBackend(SynchronousBackend[SimVehicle]):
    """:class:`SimVehicle` behind the async backend protocol; with ``step_round`` (a fleet
    host), a tick in flight waits for the round that steps the vehicle's fleet."""

    def __init__(self, vehicle: SimVehicle, step_round: StepRound | None = None) -> None:
        super().__init__(vehicle)
        self.step_round = step_round

    async def tick(self, setpoint: Setpoint | None, now_s: float) -> VehicleSnapshot:
        if self.step_round is None:
            return self.vehicle.tick(setpoint)
        if self.vehicle.begin_tick(setpoint):
            await self.step_round.stepped()
        return self.vehicle.end_tick()

    async def swap_battery(self) -> None:
        self.vehicle.swap_battery()

    async def close(self) -> None:
        self.vehicle.close()

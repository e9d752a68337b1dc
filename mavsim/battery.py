"""The simulated autopilot's battery and its two MAVLink reports (pure).

The pack is the Airshow quadrotor's (``vehicles/quadrotor_brush/battery.py``: 4S 3000 mAh), drawn
each autopilot period at the power its rotors take for the thrust they make now (momentum
theory, :mod:`sim.rotor_power`) plus its avionics: the same model as the in-process simulated
vehicle, fed the airframe's own thrust.

The reports follow what each autopilot sends (both SITLs simulate a battery and send them):

- ``SYS_STATUS``: ``voltage_battery`` [mV], ``current_battery`` [cA], ``battery_remaining`` [%];
- ``BATTERY_STATUS``: ``current_consumed`` [mAh], ``energy_consumed`` [hJ], ``battery_remaining``
  [%], ``time_remaining`` [s] at the present draw, ``charge_state``, ``temperature`` unknown
  (INT16_MAX). ArduPilot without cell monitoring puts the pack voltage in ``voltages[0]`` and
  UINT16_MAX in the other nine (``GCS_MAVLINK::send_battery_status``); PX4 sends each of its
  ``cell_count`` cells (the pack voltage shared out) and UINT16_MAX after them, and no energy
  (-1). ArduCopter's charge state comes from its pack voltage under ``BATT_LOW_VOLT`` (10.5 V by
  default); PX4's from the charge left under ``BAT_LOW_THR`` 0.15, ``BAT_CRIT_THR`` 0.07,
  ``BAT_EMERGEN_THR`` 0.05 (its defaults).

After a swap each ends its pack's count as its SITL does:

- ArduPilot counts the charge drawn (``consumed_mah``) and reports the charge left from it;
  MAV_CMD_BATTERY_RESET (``GCS_MAVLINK::handle_command_battery_reset`` ->
  ``AP_BattMonitor::reset_remaining_mask`` -> ``AP_BattMonitor_Backend::reset_remaining``, any
  time, armed or not) sets it to ``(100 - param2) %`` of the capacity and the energy to that
  charge at the last voltage: :meth:`SimBattery.reset_remaining`. SITL's own simulated pack
  (``SIM_Battery``) is untouched by it (with the default frame's zero ``SIM_BATT_CAP_AH`` its
  voltage never falls); mavsim takes a reset while disarmed on the ground as the crew's fresh
  pack, and one in the air as the counter alone.
- PX4 has no handler for 42651 (Commander answers UNSUPPORTED); its SITL battery
  (``BatterySimulator::Run``) is full again whenever the vehicle is disarmed:
  :meth:`SimBattery.refill`, each period of a disarmed PX4.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from mavsim.params import Flavor
from sim.battery import BatteryState, discharge, full
from sim.rotor_power import rotor_power_w
from vehicles.quadrotor_brush.battery import AVIONICS_W, PACK

UNKNOWN_CELL_MV = 65535
"""UINT16_MAX: a BATTERY_STATUS cell voltage not sent."""
UNKNOWN_TEMPERATURE_CDEG = 32767
"""INT16_MAX: BATTERY_STATUS temperature unknown."""
ARDUCOPTER_LOW_V = 10.5
"""ArduCopter's BATT_LOW_VOLT default, [V]."""
CHARGE_OK = mavlink.MAV_BATTERY_CHARGE_STATE_OK
PX4_THRESHOLDS = (
    (0.05, mavlink.MAV_BATTERY_CHARGE_STATE_EMERGENCY),
    (0.07, mavlink.MAV_BATTERY_CHARGE_STATE_CRITICAL),
    (0.15, mavlink.MAV_BATTERY_CHARGE_STATE_LOW),
)
"""PX4's BAT_EMERGEN_THR, BAT_CRIT_THR, BAT_LOW_THR defaults and the state under each."""


@dataclass
class SimBattery:
    """The autopilot's pack, drawn by its rotors and avionics."""

    rotors: int = 4
    rotor_radius_m: float = 0.127
    state: BatteryState = field(default_factory=lambda: full(PACK))
    """The pack in the simulated world."""
    counted_mah: float = 0.0
    """ArduPilot's ``consumed_mah`` less the charge drawn from the pack in it: nonzero after a
    MAV_CMD_BATTERY_RESET that did not come with a fresh pack [mAh]."""
    counted_wh: float = 0.0
    """The same for ArduPilot's ``consumed_wh``, [Wh]."""

    def step(self, thrust_n: float, dt_s: float) -> None:
        """Draw for one autopilot period in which the rotors make ``thrust_n`` [N] together."""
        power_w = AVIONICS_W + rotor_power_w(thrust_n, self.rotors, self.rotor_radius_m)
        self.state = discharge(PACK, self.state, power_w, dt_s)

    @property
    def consumed_mah(self) -> float:
        """ArduPilot's count of the charge drawn, [mAh]."""
        return self.state.drawn_mah + self.counted_mah

    def reset_remaining(self, percentage: float, *, fresh_pack: bool) -> None:
        """ArduPilot's ``reset_remaining(percentage)``: the count says ``percentage`` [%] left
        (clamped to 0..100), the energy drawn is that charge at the last voltage;
        ``fresh_pack``: the crew put in a pack holding that much."""
        percentage = min(max(percentage, 0.0), 100.0)
        used_fraction = (100.0 - percentage) * 0.01  # as ArduPilot computes it
        voltage_v = self.state.voltage_v
        if fresh_pack:
            left = percentage / 100.0
            self.state = BatteryState(charge_fraction=left, voltage_v=PACK.open_circuit_v(left))
        consumed_mah = used_fraction * PACK.capacity_mah
        self.counted_mah = consumed_mah - self.state.drawn_mah
        self.counted_wh = consumed_mah * 0.001 * voltage_v - self.state.drawn_wh

    def refill(self) -> None:
        """PX4 SITL's battery while disarmed: full, its count started again."""
        self.state = replace(full(PACK), current_a=self.state.current_a)
        self.counted_mah = self.counted_wh = 0.0

    @property
    def remaining_percent(self) -> int:
        """``battery_remaining`` [%]: the charge left by the count (ArduPilot's; PX4's agrees
        with the pack, its count is never reset)."""
        return round(100 * self._left_fraction)

    @property
    def _left_fraction(self) -> float:
        return max(0.0, 1.0 - self.consumed_mah / PACK.capacity_mah)

    @property
    def time_remaining_s(self) -> int:
        """Seconds until the count says empty at the present current (0: unknown, nothing
        drawn)."""
        if self.state.current_a <= 0.0:
            return 0
        left_mah = self._left_fraction * PACK.capacity_mah
        return int(left_mah * 3.6 / self.state.current_a)

    def charge_state(self, flavor: Flavor) -> int:
        """BATTERY_STATUS ``charge_state``: ArduCopter's from the pack voltage, PX4's from the
        charge left (the module's thresholds)."""
        if flavor == "ardupilot":
            low = self.state.voltage_v < ARDUCOPTER_LOW_V
            return int(mavlink.MAV_BATTERY_CHARGE_STATE_LOW if low else CHARGE_OK)
        for threshold, charge_state in PX4_THRESHOLDS:
            if self.state.charge_fraction < threshold:
                return int(charge_state)
        return int(CHARGE_OK)

    def cells_mv(self, flavor: Flavor) -> list[int]:
        """BATTERY_STATUS ``voltages`` (ten entries) as each autopilot fills them."""
        pack_mv = int(self.state.voltage_v * 1000)
        if flavor == "ardupilot":
            return [pack_mv] + [UNKNOWN_CELL_MV] * 9
        cells = PACK.cells_in_series
        return [pack_mv // cells] * cells + [UNKNOWN_CELL_MV] * (10 - cells)

    def battery_status(self, mav: mavlink.MAVLink, flavor: Flavor) -> mavlink.MAVLink_message:
        """BATTERY_STATUS as ``flavor`` sends it."""
        s = self.state
        energy_hj = int((s.drawn_wh + self.counted_wh) * 36) if flavor == "ardupilot" else -1
        return mav.battery_status_encode(
            0, mavlink.MAV_BATTERY_FUNCTION_ALL, mavlink.MAV_BATTERY_TYPE_LIPO,
            UNKNOWN_TEMPERATURE_CDEG, self.cells_mv(flavor), int(s.current_a * 100),
            int(self.consumed_mah), energy_hj, self.remaining_percent, self.time_remaining_s,
            self.charge_state(flavor),
        )  # fmt: skip

    def sys_status(
        self, mav: mavlink.MAVLink, sensors: int, healthy: int
    ) -> mavlink.MAVLink_message:
        """SYS_STATUS with ``sensors`` present and enabled, ``healthy`` healthy."""
        s = self.state
        return mav.sys_status_encode(
            sensors, sensors, healthy, 100, int(s.voltage_v * 1000), int(s.current_a * 100),
            self.remaining_percent, 0, 0, 0, 0, 0, 0,
        )  # fmt: skip

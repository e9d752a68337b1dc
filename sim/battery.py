"""LiPo battery packs (pure): open-circuit voltage by state of charge, sag under load, discharge
at a given electrical power, energy and time left.

A pack is ``cells_in_series`` equal cells, each an open-circuit voltage source ``V_oc(soc)`` behind
an internal resistance ``R`` (the equivalent circuit's series resistor; its RC branches, with time
constants of seconds to minutes, are left out: this model counts energy over minutes of flight).

Cell open-circuit voltage, state of charge ``soc`` 0..1 (Chen and Rincón-Mora, "Accurate electrical
battery model capable of predicting runtime and I-V performance", IEEE Trans. Energy Conversion
21(2), 2006, fitted to a lithium-ion polymer cell)::

    V_oc(soc) = -1.031 exp(-35 soc) + 3.685 + 0.2156 soc - 0.1178 soc^2 + 0.3201 soc^3   [V]

which gives 4.10 V full, 3.80 V at half charge and 2.65 V empty. A load drawing electrical power
``P`` takes the current ``I`` with ``P = I (V_oc - I R)``, the smaller root; the terminal voltage
sags to ``V_oc - I R``. ``charge_fraction`` is the charge left over the rated capacity (what
MAVLink's ``battery_remaining`` reports, coulomb-counted).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Literal

from sim.errors import SimError
from sim.params import positive

Phase = Literal["rest", "hover", "transit", "writing"]
"""What a vehicle does, as far as its battery goes: ``rest`` on the ground with its motors off
(avionics and companion computer); ``hover`` airborne in place, or a ground vehicle standing with
its motors on; ``transit`` moving with the pen up (flying, or driving); ``writing`` with the pen
down (brush on a board, sponge pressed on a wall, marker on the floor)."""

_OCV_EXP_V, _OCV_EXP_RATE = -1.031, 35.0
_OCV_POLY_V = (3.685, 0.2156, -0.1178, 0.3201)
"""Chen and Rincón-Mora 2006, V_oc(soc) coefficients, lowest order first, [V]."""


def cell_open_circuit_v(charge_fraction: float) -> float:
    """Open-circuit voltage of one cell in [V] at state of charge ``charge_fraction`` (0..1)."""
    s = min(1.0, max(0.0, charge_fraction))
    c0, c1, c2, c3 = _OCV_POLY_V
    return _OCV_EXP_V * math.exp(-_OCV_EXP_RATE * s) + c0 + s * (c1 + s * (c2 + s * c3))


def cell_energy_wh_per_ah(charge_fraction: float) -> float:
    """Energy in [Wh] per [Ah] of rated capacity that one cell holds from empty up to
    ``charge_fraction``, at open-circuit voltage: the integral of ``V_oc`` over the charge (closed
    form of the curve above)."""
    s = min(1.0, max(0.0, charge_fraction))
    c0, c1, c2, c3 = _OCV_POLY_V
    exp_part = _OCV_EXP_V / _OCV_EXP_RATE * (1.0 - math.exp(-_OCV_EXP_RATE * s))
    return exp_part + s * (c0 + s * (c1 / 2 + s * (c2 / 3 + s * c3 / 4)))


@dataclass(frozen=True)
class LipoPack:
    """A LiPo pack of equal cells in series."""

    cells_in_series: int
    """Cells in series (4 for a 4S pack)."""
    capacity_mah: float
    """Rated capacity in [mAh]."""
    cell_resistance_ohm: float
    """Internal (series) resistance of one cell in [Ohm]."""

    def __post_init__(self) -> None:
        if self.cells_in_series < 1:
            raise SimError(f"must be >= 1, got {self.cells_in_series}", field="cells_in_series")
        positive("capacity_mah", self.capacity_mah)
        positive("cell_resistance_ohm", self.cell_resistance_ohm)

    @property
    def resistance_ohm(self) -> float:
        """Internal resistance of the whole pack in [Ohm]."""
        return self.cells_in_series * self.cell_resistance_ohm

    def open_circuit_v(self, charge_fraction: float) -> float:
        """Pack open-circuit voltage in [V]."""
        return self.cells_in_series * cell_open_circuit_v(charge_fraction)

    def energy_wh(self, charge_fraction: float = 1.0) -> float:
        """Energy in [Wh] held from empty up to ``charge_fraction``, at open-circuit voltage."""
        ah = self.capacity_mah / 1000.0
        return self.cells_in_series * ah * cell_energy_wh_per_ah(charge_fraction)

    def max_power_w(self, charge_fraction: float) -> float:
        """Most electrical power in [W] the pack can deliver now (load matched to ``R``)."""
        v_oc = self.open_circuit_v(charge_fraction)
        return v_oc * v_oc / (4.0 * self.resistance_ohm)

    def current_a(self, charge_fraction: float, power_w: float) -> float:
        """Current in [A] a load of ``power_w`` [W] draws (``P = I (V_oc - I R)``); past the
        pack's maximum power, the current of that maximum (the voltage has collapsed)."""
        if power_w < 0.0:
            raise SimError(f"must be >= 0, got {power_w}", field="power_w")
        v_oc, r = self.open_circuit_v(charge_fraction), self.resistance_ohm
        disc = max(0.0, v_oc * v_oc - 4.0 * r * power_w)
        return (v_oc - math.sqrt(disc)) / (2.0 * r)

    def terminal_v(self, charge_fraction: float, current_a: float) -> float:
        """Voltage in [V] at the pack's terminals drawing ``current_a`` [A] (the sag)."""
        return self.open_circuit_v(charge_fraction) - current_a * self.resistance_ohm


@dataclass(frozen=True)
class PhasePowers:
    """Electrical power drawn from the pack in each :data:`Phase`, [W]."""

    rest_w: float
    hover_w: float
    transit_w: float
    writing_w: float

    def __post_init__(self) -> None:
        for name in ("rest_w", "hover_w", "transit_w", "writing_w"):
            positive(name, getattr(self, name))

    def of(self, phase: Phase) -> float:
        """Power in [W] in ``phase``."""
        return float(getattr(self, f"{phase}_w"))


@dataclass(frozen=True)
class VehicleBattery:
    """One vehicle kind's pack and what it draws: a room's ``battery.py`` defines its own."""

    pack: LipoPack
    power_w: PhasePowers
    cruise: Phase
    """The phase whose draw ``minutes left`` is counted at (``hover`` for an airborne kind: what
    it spends most of a job in; ``transit`` for a ground kind)."""


@dataclass(frozen=True)
class BatteryState:
    """A pack at one instant."""

    charge_fraction: float = 1.0
    """Charge left over the rated capacity, 0..1."""
    current_a: float = 0.0
    """Current drawn now in [A]."""
    voltage_v: float = math.nan
    """Terminal voltage now in [V] (NaN before the first :func:`discharge`: use :func:`full`)."""
    drawn_mah: float = 0.0
    """Charge drawn since the pack was put in, [mAh]."""
    drawn_wh: float = 0.0
    """Energy drawn at the terminals since the pack was put in, [Wh]."""


def full(pack: LipoPack) -> BatteryState:
    """A freshly charged pack at rest."""
    return BatteryState(charge_fraction=1.0, voltage_v=pack.open_circuit_v(1.0))


def discharge(pack: LipoPack, state: BatteryState, power_w: float, dt_s: float) -> BatteryState:
    """``state`` after drawing ``power_w`` [W] for ``dt_s`` [s] (current from the charge at the
    start of the step; an empty pack stays empty)."""
    if dt_s < 0.0:
        raise SimError(f"must be >= 0, got {dt_s}", field="dt_s")
    current_a = pack.current_a(state.charge_fraction, power_w)
    drawn_mah = current_a * dt_s / 3.6
    charge = max(0.0, state.charge_fraction - drawn_mah / pack.capacity_mah)
    voltage_v = pack.terminal_v(charge, current_a)
    return replace(
        state,
        charge_fraction=charge,
        current_a=current_a,
        voltage_v=voltage_v,
        drawn_mah=state.drawn_mah + drawn_mah,
        drawn_wh=state.drawn_wh + voltage_v * current_a * dt_s / 3600.0,
    )


def minutes_left(pack: LipoPack, charge_fraction: float, power_w: float) -> float:
    """Minutes until empty drawing ``power_w`` [W] from ``charge_fraction``: the energy left, less
    the share the internal resistance turns into heat at today's current, over the power."""
    positive("power_w", power_w)
    current_a = pack.current_a(charge_fraction, power_w)
    v_oc = pack.open_circuit_v(charge_fraction)
    delivered = pack.terminal_v(charge_fraction, current_a) / v_oc if v_oc > 0.0 else 0.0
    return 60.0 * pack.energy_wh(charge_fraction) * delivered / power_w

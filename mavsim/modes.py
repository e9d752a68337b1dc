"""ArduCopter flight modes (HEARTBEAT custom_mode) that the simulated autopilot knows."""

from __future__ import annotations

from enum import IntEnum


class CopterMode(IntEnum):
    """ArduCopter custom mode numbers."""

    STABILIZE = 0
    ALT_HOLD = 2
    AUTO = 3
    GUIDED = 4
    LOITER = 5
    RTL = 6
    LAND = 9
    BRAKE = 17


HOLDING_MODES = frozenset({CopterMode.STABILIZE, CopterMode.ALT_HOLD, CopterMode.LOITER,
                           CopterMode.BRAKE, CopterMode.AUTO})  # fmt: skip
"""Modes in which this simulator simply holds position (no pilot sticks, no mission)."""

NEEDS_POSITION = frozenset({CopterMode.GUIDED, CopterMode.LOITER, CopterMode.BRAKE,
                            CopterMode.RTL, CopterMode.AUTO})  # fmt: skip
"""Modes refused, when armed, before the estimator has a position source."""

NOT_ARMABLE = frozenset({CopterMode.LAND, CopterMode.RTL, CopterMode.AUTO})
"""Modes in which arming is refused (ArduPilot: "Mode not armable")."""


def mode_name(custom_mode: int) -> str:
    """Upper-case name of a custom mode, or ``MODE<n>`` when unknown."""
    try:
        return CopterMode(custom_mode).name
    except ValueError:
        return f"MODE{custom_mode}"


PX4_MODES: dict[CopterMode, tuple[int, int]] = {
    CopterMode.STABILIZE: (1, 0),  # MANUAL
    CopterMode.ALT_HOLD: (2, 0),  # ALTCTL
    CopterMode.BRAKE: (3, 0),  # POSCTL (no sticks: holds)
    CopterMode.AUTO: (4, 4),  # AUTO.MISSION
    CopterMode.LOITER: (4, 3),  # AUTO.LOITER (Hold)
    CopterMode.RTL: (4, 5),  # AUTO.RTL
    CopterMode.LAND: (4, 6),  # AUTO.LAND
    CopterMode.GUIDED: (6, 0),  # OFFBOARD
}
"""How a PX4 vehicle shows each mode: (main mode, sub mode) of its custom_mode."""


def px4_custom_mode(mode: CopterMode) -> int:
    """HEARTBEAT custom_mode of a PX4 vehicle in ``mode``: main << 16 | sub << 24."""
    main, sub = PX4_MODES[mode]
    return (main << 16) | (sub << 24)


def from_px4(main: int, sub: int) -> CopterMode | None:
    """The mode a PX4 (main, sub) pair selects (sub ignored outside AUTO), None if unknown."""
    for mode, (m, s) in PX4_MODES.items():
        if m == main and (main != 4 or s == sub):
            return mode
    return None

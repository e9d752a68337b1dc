"""Show files: YAML validated once at start into typed objects; errors name file, line and field.

>>> show = load_show("shows/airshow-2014.yaml")   # doctest: +SKIP
>>> show.vehicle("uav1").board
'b1'
"""

from showfile.loader import (
    ShowError,
    ShowFileError,
    ShowProblem,
    dump_show,
    load_show,
    parse_show,
)
from showfile.models import (
    Board,
    ControllerSettings,
    KioskSettings,
    Limits,
    MavlinkSimSettings,
    PlanningSettings,
    PolicySettings,
    Show,
    StorageSettings,
    Vehicle,
    ZenohSettings,
)
from showfile.security import SecuritySettings

__all__ = [
    "Board",
    "ControllerSettings",
    "KioskSettings",
    "Limits",
    "MavlinkSimSettings",
    "PlanningSettings",
    "PolicySettings",
    "SecuritySettings",
    "Show",
    "ShowError",
    "ShowFileError",
    "ShowProblem",
    "StorageSettings",
    "Vehicle",
    "ZenohSettings",
    "dump_show",
    "load_show",
    "parse_show",
]

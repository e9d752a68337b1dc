"""Show files: YAML validated once at start into typed objects; errors name file, line and field.

>>> show = load_show("shows/airshow-2014.yaml")   # doctest: +SKIP
>>> show.vehicle("uav1").board
'b1'

The names below are imported on first use (PEP 562): importing a light module of the package
(:mod:`showfile.bus_view`, :mod:`showfile.errors`, :mod:`showfile.roles`) does not load the
models and pydantic.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from showfile.errors import ShowError
    from showfile.loader import ShowFileError, ShowProblem, dump_show, load_show, parse_show
    from showfile.models import (
        Board,
        ControllerSettings,
        Limits,
        MavlinkSimSettings,
        PlanningSettings,
        Show,
        Vehicle,
    )
    from showfile.security import SecuritySettings
    from showfile.services import KioskSettings, PolicySettings, StorageSettings, ZenohSettings

_MODULE_OF = {
    "ShowError": "showfile.errors",
    **dict.fromkeys(
        ("ShowFileError", "ShowProblem", "dump_show", "load_show", "parse_show"), "showfile.loader"
    ),
    **dict.fromkeys(
        (
            "Board",
            "ControllerSettings",
            "Limits",
            "MavlinkSimSettings",
            "PlanningSettings",
            "Show",
            "Vehicle",
        ),
        "showfile.models",
    ),
    **dict.fromkeys(
        ("KioskSettings", "PolicySettings", "StorageSettings", "ZenohSettings"), "showfile.services"
    ),
    "SecuritySettings": "showfile.security",
}

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


def __getattr__(name: str) -> Any:
    module = _MODULE_OF.get(name)
    if module is None:
        raise AttributeError(f"module 'showfile' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})

"""The ``autopilot`` fixture: every conformance test runs against each autopilot.

- ``mavsim-ardupilot``, ``mavsim-px4``: the project's MAVLink simulator, started here in-process
  (UDP on loopback, position estimate ready at once), at ``MAVSIM_TIME_SCALE`` times real time:
  the ground station counts the vehicle's own seconds (``clock``), so every wait, rate and timeout
  of a test means the same seconds to the vehicle as at real time;
- ``sitl-ardupilot``, ``sitl-px4`` (marked ``sitl``): ArduCopter SITL and PX4 SITL from
  ``tests/conformance/sitl_targets.py`` (``start_sitl(kind)``), which skips with its reason when
  the binaries are not configured; without that module they are skipped too.

The fixture yields an object with ``kind`` (``ardupilot``/``px4``), ``url`` (a pymavlink connection
string), ``system_id``, ``clock()`` (the vehicle's time in [s]) and ``close()``; each test gets a
fresh vehicle, on the ground, disarmed.
"""

from __future__ import annotations

import importlib.util
import sys
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

from mavsim.config import VehicleConfig
from mavsim.server import MavsimServer

SITL_TARGETS = Path(__file__).with_name("sitl_targets.py")
MAVSIM_SYSTEM_ID = 7
MAVSIM_TIME_SCALE = 4.0
"""Vehicle seconds per wall second for mavsim: the suite's 38 flights took 220 s at real time."""


@dataclass
class MavsimTarget:
    """A simulated vehicle served by mavsim on a free UDP port."""

    kind: str
    """``ardupilot`` or ``px4``."""
    server: MavsimServer = field(repr=False)
    """The running simulator."""

    @property
    def url(self) -> str:
        """We send first; the vehicle answers whoever spoke to it."""
        endpoint = self.server.endpoints[0]
        return f"udpout:{endpoint.config.host}:{endpoint.port}"

    @property
    def system_id(self) -> int:
        return self.server.endpoints[0].config.system_id

    def clock(self) -> float:
        """The vehicle's time in [s] (mavsim's, which slows down rather than jump when the
        machine falls behind)."""
        return self.server.vehicle_time_s()

    def close(self) -> None:
        if self.server is not None:
            self.server.stop()


def start_mavsim(kind: str) -> MavsimTarget:
    config = VehicleConfig(vehicle_id=f"mavsim-{kind}", system_id=MAVSIM_SYSTEM_ID, port=0,
                           autopilot=kind, position_source_delay_s=0.0)  # type: ignore[arg-type]  # fmt: skip
    return MavsimTarget(kind, MavsimServer([config], time_scale=MAVSIM_TIME_SCALE).start())


def _sitl_targets() -> ModuleType | None:
    """tests/conformance/sitl_targets.py, loaded by path (None when it is not there)."""
    if not SITL_TARGETS.is_file():
        return None
    name = "tests.conformance.sitl_targets"
    module = sys.modules.get(name)
    if module is None:
        spec = importlib.util.spec_from_file_location(name, SITL_TARGETS)
        if spec is None or spec.loader is None:
            return None
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return module


@pytest.fixture(
    params=[
        "mavsim-ardupilot",
        "mavsim-px4",
        pytest.param("sitl-ardupilot", marks=pytest.mark.sitl),
        pytest.param("sitl-px4", marks=pytest.mark.sitl),
    ]
)
def autopilot(request: pytest.FixtureRequest) -> Iterator[Any]:
    """A fresh autopilot on the ground (see the module docstring)."""
    source, kind = str(request.param).split("-", 1)
    if source == "mavsim":
        target: Any = start_mavsim(kind)
    else:
        module = _sitl_targets()
        if module is None:
            pytest.skip("sitl_targets not available")
        target = module.start_sitl(kind)
    try:
        yield target
    finally:
        target.close()

"""Routes between floor areas: refused with one clear line when out of reach; driven across a
step with the marker up."""

from __future__ import annotations

import numpy as np
import pytest

from vehicles.omni_wheel.check_route import FloorArea, RouteError, check_route
from vehicles.omni_wheel.floor_plan import OmniSettings
from vehicles.omni_wheel.route import drive_route
from vehicles.omni_wheel.terrain import Step, Terrain
from vehicles.omni_wheel.writing import FloorWriter

TERRAIN = Terrain(steps=(Step(2.0, 0.05), Step(5.0, 0.3)), half_width_m=10.0)


def test_reachable_area_passes() -> None:
    check_route((0.0, 0.0, 0.0), FloorArea("plaza", (3.5, 1.0, 0.05), 1.0), TERRAIN)


@pytest.mark.parametrize(
    ("area", "message"),
    [
        (
            FloorArea("top", (7.0, 0.0, 0.3), 1.0),
            "out of reach: the step at x=5.00 m is 0.250 m high",
        ),
        (FloorArea("far", (70.0, 0.0, 0.3), 1.0), "out of reach: 70.0 m of route"),
        (FloorArea("edge", (2.3, 0.0, 0.05), 1.0), "straddles the step edge at x=2.00 m"),
        (FloorArea("side", (3.5, 9.5, 0.05), 1.0), "lies off the terrain"),
        (
            FloorArea("air", (3.5, 0.0, 0.5), 1.0),
            "is at height 0.500 m but the floor there is 0.050 m",
        ),
    ],
)
def test_unreachable_areas_are_refused_in_one_line(area: FloorArea, message: str) -> None:
    with pytest.raises(RouteError, match=message) as caught:
        check_route((0.0, 0.0, 0.0), area, TERRAIN)
    text = str(caught.value)
    assert "\n" not in text and repr(area.name) in text


@pytest.mark.slow
def test_transit_climbs_the_step_to_the_next_area() -> None:
    settings = OmniSettings(terrain=Terrain(steps=(Step(1.0, 0.05),)))
    writer = FloorWriter(settings, np.array([0.0, 0.0, 0.0]), seed=4)
    result = drive_route(writer, (2.0, 0.5, 0.05))
    assert result.arrived
    np.testing.assert_allclose(result.path_m_enu[-1][:2], [2.0, 0.5], atol=0.02)
    # the middle axle ends on the upper level: step height plus wheel radius
    assert result.base_m_enu[-1][2] == pytest.approx(0.05 + 0.066, abs=0.005)

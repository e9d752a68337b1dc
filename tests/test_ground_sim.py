"""The ground writer in MuJoCo: rollers give omnidirectional motion on the flat with traction only
along each wheel's drive direction; the proposed wheel control climbs the paper's 0.1 m step."""

from __future__ import annotations

import numpy as np
import pytest

from vehicles.omni_wheel.climb import climb
from vehicles.omni_wheel.geometry import OmniGeometry
from vehicles.omni_wheel.model import Terrain
from vehicles.omni_wheel.sim import OmniWorld
from vehicles.omni_wheel.wheel_control import BodyConfiguration, proposed_references

GEO = OmniGeometry()
RUBBER = OmniGeometry(friction_static=1.0)


def _drive(refs: np.ndarray, seconds: float) -> np.ndarray:
    world = OmniWorld(GEO, Terrain(), ((0.0, 0.0, 0.0, 0.0),), seed=3)
    start = world.truth(0).base_m_enu
    while world.t_s < seconds:
        world.step(refs[None, :])
    return world.truth(0).base_m_enu - start


def test_sideways_wheel_alone_moves_the_vehicle_sideways() -> None:
    # only the front-centre wheel drives (along y); the six x wheels hold still on their motors:
    # their rollers must let the body slide sideways
    refs = proposed_references(np.array([0.0, 0.1, 0.0]), BodyConfiguration(), GEO).rate_radps
    assert np.count_nonzero(np.abs(refs) > 1e-9) == 1
    moved = _drive(refs, 2.0)
    assert moved[1] > 0.12  # 0.2 m commanded; the one wheel slips a little
    assert abs(moved[0]) < 0.02


def test_x_wheels_drive_straight_ahead() -> None:
    refs = proposed_references(np.array([0.2, 0.0, 0.0]), BodyConfiguration(), GEO).rate_radps
    moved = _drive(refs, 2.0)
    assert moved[0] == pytest.approx(0.4, abs=0.04)
    assert abs(moved[1]) < 0.02


@pytest.mark.slow
def test_proposed_method_climbs_the_papers_step() -> None:
    result = climb("proposed", 0.1, geometry=RUBBER)
    assert result.climbed
    assert result.duration_s < 8.0
    # the references follow the body configuration: while the front part swings up, eq. 15
    # slows the middle wheels well below V0 / r (the standard method never changes them)
    middle = result.log["reference_radps"][:, 3]
    assert middle.min() < 0.6 * GEO.running_speed_mps / GEO.wheel_radius_m
    assert np.all(np.isfinite(result.slip_per_wheel[[0, 2, 3, 4, 5, 6]]))


@pytest.mark.slow
def test_table_1_friction_cannot_climb_half_a_wheel() -> None:
    # with the rollers' 0.3 of Table 1 the traction of all seven wheels cannot lift a wheel onto
    # a 50 mm step: the run ends stuck in front of it
    result = climb("proposed", 0.05, time_limit_s=6.0)
    assert not result.climbed
    assert result.log["base_m_enu"][-1, 0] < 0.35

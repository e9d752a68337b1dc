"""The geofence alone: built from a board, a home and margins; points in and out; plans; the
guard's verdict on a vehicle at its boundary (within the position's resolution: no breach)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from showfile import load_show
from showfile.checks import footprint
from showfile.geofence import convex_hull, show_fence
from vehicle_agent.backends.base import VehicleSnapshot
from vehicle_agent.safety import Geofence, GeofenceError, SafetyLimits, vehicle_fence
from vehicle_agent.safety.geofence import BOUNDARY_TOLERANCE_M, FenceWatch
from vehicle_agent.safety.guard import Breach, SafetyGuard

BOARD = [(-0.7, -0.7), (0.7, -0.7), (0.7, 0.7), (-0.7, 0.7)]
HOME = (0.0, -1.2, 0.0)


def fence() -> Geofence:
    return vehicle_fence(BOARD, HOME, 1.05, margin_m=0.5, ceiling_margin_m=0.5)


def test_the_fence_covers_board_home_and_transit_with_its_margins() -> None:
    f = fence()
    for inside in [(0.0, 0.0, 1.0), (0.7 + 0.49, 0.0, 1.0), (0.0, -1.2 - 0.49, 0.5),
                   (0.0, -0.95, 1.05), (0.0, 0.0, 1.05 + 0.49), (0.0, -1.2, -0.1)]:  # fmt: skip
        assert f.contains(inside), inside
    for outside, distance in [((0.7 + 0.6, 0.0, 1.0), 0.1), ((0.0, 0.0, 1.05 + 0.7), 0.2),
                              ((0.0, 0.7 + 0.8, 1.0), 0.3), ((0.0, 0.0, -0.5), 0.3)]:  # fmt: skip
        assert not f.contains(outside), outside
        assert f.distance_outside_m(outside) == pytest.approx(distance, abs=0.02)
    assert math.isinf(f.distance_outside_m((math.nan, 0.0, 1.0)))


def test_first_outside_finds_the_first_sample_that_leaves() -> None:
    f = fence()
    points = np.array([[0.0, 0.0, 1.0], [0.5, 0.5, 1.0], [3.0, 0.0, 1.0], [0.0, 0.0, 9.0]])
    assert f.first_outside(points) == 2
    assert f.first_outside(points[:2]) is None
    assert f.first_outside(np.empty((0, 3))) is None


@settings(max_examples=200, deadline=None)
@given(x=st.floats(-3, 3), y=st.floats(-3, 3), z=st.floats(-1, 3))
def test_vectorised_and_scalar_checks_agree(x: float, y: float, z: float) -> None:
    f = fence()
    assert (f.first_outside(np.array([[x, y, z]])) is None) == f.contains((x, y, z))


@settings(max_examples=200, deadline=None)
@given(
    start=st.tuples(st.floats(-3, 3), st.floats(-3, 3), st.floats(-1, 3)),
    steps=st.lists(
        st.tuples(st.floats(-0.3, 0.3), st.floats(-0.3, 0.3), st.floats(-0.2, 0.2)),
        min_size=1,
        max_size=60,
    ),
)
def test_a_watch_along_a_flight_judges_every_point_as_the_fence_does(
    start: tuple[float, float, float], steps: list[tuple[float, float, float]]
) -> None:
    f = fence()
    watch = FenceWatch(f)
    p = np.array(start)
    for step in steps:  # in and out of the fence, across its edges, by small and large moves
        p = p + np.array(step)
        assert watch.distance_outside_m(p) == f.distance_outside_m(p)
    assert watch.distance_outside_m((math.nan, 0.0, 1.0)) == math.inf


def test_a_watch_reads_the_edges_again_only_near_them() -> None:
    f = fence()
    watch = FenceWatch(f)
    reads = 0
    edge_offset_m = f.edge_offset_m

    def counted(x_m: float, y_m: float) -> float:
        nonlocal reads
        reads += 1
        return edge_offset_m(x_m, y_m)

    object.__setattr__(f, "edge_offset_m", counted)
    for k in range(200):  # 1 cm per tick over the board's middle
        assert watch.distance_outside_m((-0.5 + 0.005 * k, 0.0, 1.0)) == 0.0
    assert reads < 10  # a fresh check at every tick: 200 (two reads each)


def test_hull_is_counter_clockwise_and_drops_inner_points() -> None:
    hull = convex_hull([(0, 0), (1, 0), (1, 1), (0, 1), (0.5, 0.5), (0.5, 0.0)])
    assert hull == ((0, 0), (1, 0), (1, 1), (0, 1))


def test_a_fence_without_area_or_with_a_bad_margin_is_refused() -> None:
    with pytest.raises(GeofenceError, match="no area"):
        vehicle_fence([(0.0, 0.0)], (0.0, 0.0, 0.0), 1.0, margin_m=0.0, ceiling_margin_m=0.5)
    with pytest.raises(GeofenceError, match=">= 0"):
        vehicle_fence(BOARD, HOME, 1.0, margin_m=-1.0, ceiling_margin_m=0.5)


def test_each_shipped_vehicles_fence_holds_its_board_and_home_but_not_its_neighbours() -> None:
    show = load_show("shows/airshow-2014.yaml")
    fences = {}
    for vehicle in show.vehicles:
        board = show.board(vehicle.board)
        f = show_fence(show, vehicle.id, 1.05)
        assert f.contains((*board.center_m_enu[:2], 1.0)) and f.contains(vehicle.home_m_enu)
        fences[vehicle.id] = (f, board)
    f1, _ = fences["uav1"]
    _, b3 = fences["uav3"]
    assert not f1.contains((*b3.center_m_enu[:2], 1.0))


def test_a_ground_writers_fence_holds_the_corners_of_its_sideways_first_transit() -> None:
    """The omni-wheel vehicle drives along world y first, then x: the corner of that L lies
    outside the hull of its board and home alone, and inside its fence."""
    mixed = load_show("shows/mixed.yaml")
    i, vehicle = next((i, v) for i, v in enumerate(mixed.vehicles) if v.kind == "omni-wheel")
    board = mixed.board(vehicle.board)
    vehicle = vehicle.model_copy(update={"home_m_enu": (board.center_m_enu[0] - 2.5, -1.5, 0.0)})
    vehicles = [*mixed.vehicles[:i], vehicle, *mixed.vehicles[i + 1 :]]
    show = mixed.model_copy(update={"vehicles": vehicles})
    corner_m_enu = (vehicle.home_m_enu[0], board.center_m_enu[1], vehicle.home_m_enu[2])
    straight = vehicle_fence(
        footprint(board), vehicle.home_m_enu, 0.5, margin_m=0.0, ceiling_margin_m=0.5
    )
    assert not straight.contains(corner_m_enu)
    assert show_fence(show, vehicle.id, 0.5).contains(corner_m_enu)


def judged(f: Geofence, position_m_enu: np.ndarray) -> Breach | None:
    """The guard's verdict on a vehicle flying a transit at ``position_m_enu``."""
    x, y, z = (float(v) for v in position_m_enu)
    guard = SafetyGuard(SafetyLimits(fence=f))
    snapshot = VehicleSnapshot(t_s=1.0, position_m_enu=(x, y, z), velocity_mps_enu=(0.0, 0.0, 0.0),
                               armed=True, mode="offboard", on_ground=False)  # fmt: skip
    return guard.check("transit", snapshot, None, 1.0)


def on_an_edge(f: Geofence) -> tuple[np.ndarray, np.ndarray]:
    """The middle of the fence's first edge at mid-height, and the edge's outward unit normal."""
    (x0, y0), (x1, y1) = f.polygon_xy_m[0], f.polygon_xy_m[1]
    length = math.hypot(x1 - x0, y1 - y0)
    middle = np.array([(x0 + x1) / 2, (y0 + y1) / 2, (f.floor_z_m + f.ceiling_z_m) / 2])
    return middle, np.array([(y1 - y0) / length, -(x1 - x0) / length, 0.0])  # right: outside


def test_a_vehicle_on_the_boundary_or_within_its_resolution_outside_is_not_a_breach() -> None:
    f = fence()
    middle, outward = on_an_edge(f)
    ceiling, up = np.array([0.0, 0.0, f.ceiling_z_m]), np.array([0.0, 0.0, 1.0])
    for on_boundary, out in [(middle, outward), (ceiling, up)]:
        for position in (on_boundary, on_boundary + 0.9 * BOUNDARY_TOLERANCE_M * out):
            assert judged(f, position) is None, position
            # as an autopilot reports it: rounded to float32 (LOCAL_POSITION_NED)
            assert judged(f, position.astype(np.float32)) is None, position


def test_a_vehicle_beyond_the_resolution_is_a_breach_named_in_millimetres() -> None:
    f = fence()
    middle, outward = on_an_edge(f)
    for outside_m, words in [(1.5 * BOUNDARY_TOLERANCE_M, "by 0.01 mm at"),
                             (0.0042, "by 4.2 mm at"), (0.25, "by 250.0 mm at")]:  # fmt: skip
        breach = judged(f, middle + outside_m * outward)
        assert breach is not None and breach.code == "geofence", outside_m
        assert f"outside its geofence {words}" in breach.message, breach.message
    above = judged(f, np.array([0.0, 0.0, f.ceiling_z_m + 0.001]))
    assert above is not None and "by 1.0 mm" in above.message

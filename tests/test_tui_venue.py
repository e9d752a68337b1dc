"""The console's venue plan: the show's boards, homes and geofences to scale, vehicles where they
are, at 80x24 and in the running console (issue 36)."""

from __future__ import annotations

import asyncio
import re
from typing import Any

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from bus.messages import Telemetry
from showfile import load_show
from tui.app import ConsoleApp
from tui.model import ConsoleModel
from tui.settings import settings_from_show
from tui.venue import VehicleMark, Venue, VenueArea, VenueVehicle, draw_venue, venue_from_show
from tui.widgets.confirm_screen import ConfirmScreen
from tui.widgets.venue_screen import VenueScreen

pytestmark = pytest.mark.timeout(60)
MIXED = load_show("shows/mixed.yaml")


def _lines(venue: Venue, marks: list[VehicleMark], cols: int, rows: int) -> list[str]:
    return draw_venue(venue, marks, cols, rows).plain.split("\n")


def _square_venue(side_m: float) -> Venue:
    board = ((0.0, 0.0), (side_m, 0.0), (side_m, side_m), (0.0, side_m))
    return Venue(areas=(VenueArea("b1", "horizontal", board),))


def test_the_mixed_show_fits_80x24_with_every_vehicle_labelled_where_it_is() -> None:
    venue = venue_from_show(MIXED)
    marks = [VehicleMark(v.id, "idle", v.home_m_enu) for v in MIXED.vehicles]  # each at its home
    lines = _lines(venue, marks, 80, 20)
    assert len(lines) == 20 and all(len(line) <= 80 for line in lines)
    picture = "\n".join(lines[:-3])
    for label in "1234":
        assert picture.count(label) == 1, label
    assert re.search(r"├─+┤ [\d.]+ m", lines[-3])
    assert "1 uav1 idle" in lines[-2] and "4 ground1 idle" in lines[-1]


@settings(max_examples=60, deadline=None)
@given(
    a=st.tuples(st.floats(0.0, 10.0), st.floats(0.0, 10.0)),
    b=st.tuples(st.floats(0.0, 10.0), st.floats(0.0, 10.0)),
)
def test_north_is_up_and_east_is_right(a: tuple[float, float], b: tuple[float, float]) -> None:
    """Two vehicles over a 10 m board: the one further east is further right, the one further
    north higher up (whenever they are more than two cells apart)."""
    assume(max(abs(a[0] - b[0]), abs(a[1] - b[1])) > 1.0)  # not in one cell
    venue = Venue(
        areas=_square_venue(10.0).areas,
        vehicles=(VenueVehicle("v1", (0.0, 0.0), ()), VenueVehicle("v2", (10.0, 10.0), ())),
    )
    marks = [VehicleMark("v1", "writing", (*a, 1.0)), VehicleMark("v2", "writing", (*b, 1.0))]
    lines = _lines(venue, marks, 80, 20)[:-2]  # the plan: the scale bar and roster below
    where = {
        label: (row, line.index(label))
        for row, line in enumerate(lines)
        for label in "12"
        if label in line
    }
    (row1, col1), (row2, col2) = where["1"], where["2"]
    cells_per_m_x, cells_per_m_y = (col2 - col1), (row2 - row1)
    if abs(b[0] - a[0]) > 1.0:  # > 2 cells at this scale (80 columns over ~10 m)
        assert (cells_per_m_x > 0) == (b[0] > a[0])
    if abs(b[1] - a[1]) > 2.0:  # rows are 4 dots: half as fine as columns
        assert (cells_per_m_y < 0) == (b[1] > a[1])


@pytest.mark.parametrize("side_m", [1.4, 6.0, 40.0])
def test_the_scale_bar_measures_the_board(side_m: float) -> None:
    """A square board's width on screen, read with the printed scale bar, is its width."""
    lines = _lines(_square_venue(side_m), [], 80, 24)
    bar = next(line for line in lines if "├" in line)
    match = re.match(r"├(─*)┤ ([\d.]+) m", bar)
    assert match
    cells_per_m = (len(match.group(1)) + 2) / float(match.group(2))
    top = next(line for line in lines if line.strip())
    board_cells = len(top.strip())
    assert board_cells / cells_per_m == pytest.approx(side_m, rel=0.15, abs=0.6 / cells_per_m)


def test_a_fleet_larger_than_the_roster_says_how_many_are_left_out() -> None:
    vehicles = tuple(VenueVehicle(f"v{i}", (0.1 * i, 0.0), ()) for i in range(250))
    lines = _lines(Venue(_square_venue(25.0).areas, vehicles), [], 80, 22)
    assert len(lines) == 22 and re.search(r"\+\d+ more", lines[-1])


def test_the_console_opens_the_plan_on_m_keeps_e_stop_and_goes_back_on_q() -> None:
    show_settings = settings_from_show(MIXED)
    model = ConsoleModel(show_settings)
    for vehicle in MIXED.vehicles:
        x, y, _ = vehicle.home_m_enu
        telemetry = Telemetry(
            vehicle_id=vehicle.id,
            t_s=100.0,
            state="writing",
            position_m_enu=(x, y + 0.3, 1.0),
            velocity_mps_enu=(0.0, 0.0, 0.0),
        )
        model.apply(telemetry, 100.0)
    app = ConsoleApp(show_settings, model=model, clock=lambda: 100.0)

    async def main() -> None:
        async with app.run_test(size=(80, 24)) as pilot:
            await pilot.pause()
            await pilot.press("m")
            for _ in range(3):
                await pilot.pause(0.02)
            assert isinstance(app.screen, VenueScreen)
            shown = _screen_text(app)
            for label in ("1 uav1", "2 uav2", "3 calligrap", "4 ground1"):
                assert label in shown, label
            await pilot.press("e")
            await pilot.pause(0.05)
            assert isinstance(app.screen, ConfirmScreen)  # E-STOP asks, even from the plan
            await pilot.press("escape")
            await pilot.pause(0.05)
            await pilot.press("q")
            await pilot.pause(0.05)
            assert not isinstance(app.screen, VenueScreen) and app.is_running

    asyncio.run(main())


def _screen_text(app: Any) -> str:
    view = app.screen.query_one("#venue-plan")
    size = view.content_size
    return draw_venue(app.settings.venue, view._marks, size.width, size.height).plain

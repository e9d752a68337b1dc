"""The wall writer's force in the console: the plot's numbers and what a show file says each
vehicle writes on (the Textual and Zenoh path is in test_tui_console.py)."""

from __future__ import annotations

import math
from pathlib import Path

from hypothesis import example, given
from hypothesis import strategies as st

from bus.messages import Telemetry
from showfile import load_show
from tui.braille import BrailleCanvas
from tui.model import ConsoleModel
from tui.settings import ConsoleSettings, VehicleSpec, settings_from_show
from tui.tracks import TrackPoint
from tui.widgets.force_plot import MEASURED, TARGET, force_series, plot_force
from tui.widgets.vehicle_detail_screen import VehicleDetailScreen

SHOWS = Path(__file__).resolve().parents[1] / "shows"


def _point(force_n: float | None, target_n: float | None) -> TrackPoint:
    return TrackPoint((0.0, 0.0, 0.0), None, True, force_n, target_n)


def _highest_dot(canvas: BrailleCanvas, x: int, layer: int) -> int | None:
    rows = [y for y in range(canvas.height_dots) if canvas.get(x, y, layer)]
    return min(rows) if rows else None


def test_each_column_shows_the_last_sample_that_falls_in_it() -> None:
    points = [_point(float(i), 10.0) for i in range(10)]
    measured, target = force_series(points, 5)
    assert measured == [1.0, 3.0, 5.0, 7.0, 9.0]
    assert target == [10.0] * 5
    assert force_series([], 3) == ([None] * 3, [None] * 3)
    # fewer samples than columns: samples repeat, the last column is the newest
    assert force_series(points[:2], 4)[0] == [0.0, 0.0, 1.0, 1.0]


def test_a_force_under_its_target_is_drawn_under_it_on_a_scale_from_zero() -> None:
    canvas, top_n = plot_force([2.0] * 20, [4.0] * 20, cols=10, rows=4)
    assert top_n == 4.4  # a tenth above the largest value
    bottom = canvas.height_dots - 1
    for x in range(canvas.width_dots):
        assert _highest_dot(canvas, x, TARGET) == round(bottom * (1 - 4.0 / 4.4))
        assert _highest_dot(canvas, x, MEASURED) == round(bottom * (1 - 2.0 / 4.4))


def test_samples_without_force_leave_gaps() -> None:
    canvas, _ = plot_force([1.0, None, None, 1.0], [None] * 4, cols=2, rows=2)
    assert [_highest_dot(canvas, x, MEASURED) is not None for x in range(4)] == [
        True,
        False,
        False,
        True,
    ]


@given(st.lists(st.one_of(st.none(), st.floats(allow_nan=True)), min_size=1, max_size=60))
@example([1.7e308, -math.inf, math.nan, None, 3.0])
def test_every_finite_force_lands_on_the_plot(values: list[float | None]) -> None:
    """Whatever a vehicle sends (negative, huge, NaN, infinite): no crash, and every finite
    value gets a dot."""
    canvas, top_n = plot_force(values, values, cols=30, rows=3)
    assert math.isfinite(top_n) and top_n >= 1.0
    for x, value in enumerate(values[: canvas.width_dots]):
        shown = value is not None and math.isfinite(value)
        assert (_highest_dot(canvas, x, MEASURED) is not None) == shown


def test_the_show_file_says_what_each_vehicle_writes_on() -> None:
    show = load_show(SHOWS / "airshow-2014.yaml")
    orientations = ("horizontal", "vertical", "floor")
    boards = [
        b.model_copy(update={"orientation": orientations[i % 3]}) for i, b in enumerate(show.boards)
    ]
    settings = settings_from_show(show.model_copy(update={"boards": boards}))
    named = {b.id: ("board", "wall", "floor")[i % 3] for i, b in enumerate(show.boards)}
    assert settings.vehicles
    for spec in settings.vehicles:
        assert spec.surface == named[spec.board_id or ""]


def test_a_force_off_its_target_alerts_only_while_writing() -> None:
    settings = ConsoleSettings(
        show_id="s", vehicles=(VehicleSpec("hexa1", "hexarotor-sponge", "w", "wall"),)
    )
    model = ConsoleModel(settings)

    def telemetry(state: str, force_n: float, target_n: float) -> Telemetry:
        return Telemetry(
            vehicle_id="hexa1",
            t_s=0.0,
            state=state,  # type: ignore[arg-type]
            position_m_enu=(0.0, 0.0, 1.0),
            velocity_mps_enu=(0.0, 0.0, 0.0),
            job_id="j",
            force_n=force_n,
            force_reference_n=target_n,
        )

    model.apply(telemetry("writing", 3.5, 4.0), 0.0)
    assert not model.alerts()
    model.apply(telemetry("writing", 2.5, 4.0), 0.1)
    assert [a.kind for a in model.alerts()] == ["force_error"]
    model.apply(telemetry("returning", 0.0, 4.0), 0.2)
    assert not model.alerts()
    row = model.vehicle_row("hexa1", 0.2)
    assert row is not None and row.surface == "wall" and row.force_n == 0.0


def test_a_detail_screen_not_yet_composed_skips_its_redraw() -> None:
    # The console's tick can reach a just-pushed detail screen before Textual has composed it
    # (CI saw NoMatches '#detail-info' once): the redraw waits for the next tick.
    settings = ConsoleSettings(show_id="s", vehicles=(VehicleSpec("uav1", "quadrotor-brush", "b"),))
    screen = VehicleDetailScreen("uav1", ConsoleModel(settings), None)
    screen.sync(0.0)
    assert not screen.children

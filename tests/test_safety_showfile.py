"""The show's ``safety`` section: defaults so shipped shows need nothing, errors that name it."""

from __future__ import annotations

from pathlib import Path

import pytest

from showfile import ShowError, load_show, parse_show
from showfile.safety import SafetySettings
from vehicle_agent.setup import vehicle_setup

SHOWS = Path(__file__).resolve().parents[1] / "shows"
BASE = """show_id: s
boards: [{id: b1, center_m_enu: [0, 0, 0.75], size_m: [1.4, 1.4], writing_area_m: [1, 1]}]
vehicles: [{id: u1, board: b1, home_m_enu: [0, -1.2, 0]}]
"""


@pytest.mark.parametrize("name", ["airshow-2014.yaml", "solo.yaml", "rehearsal-mavlink.yaml"])
def test_shipped_shows_get_the_defaults_and_a_fence_around_board_and_home(name: str) -> None:
    show = load_show(SHOWS / name)
    assert show.safety == SafetySettings()
    for vehicle in show.vehicles:
        safety = vehicle_setup(show, vehicle.id).runner_config.safety
        assert safety.fence is not None and safety.fence.contains(vehicle.home_m_enu)
        assert safety.fence.contains((*show.board(vehicle.board).center_m_enu[:2], 1.0))
        assert (safety.deviation.bound_m, safety.writing.rmse_pen_down_max_m) == (0.15, 0.05)


def test_a_safety_section_is_read_into_the_vehicles_limits() -> None:
    show = parse_show(BASE + "safety: {deviation_bound_m: 0.1, abort_policy: hold, iou_min: 0.5,"
                      " fence_margin_m: 0.2, settle_attempts: 3}\n")  # fmt: skip
    safety = vehicle_setup(show, "u1").runner_config.safety
    assert (safety.deviation.bound_m, safety.abort_policy, safety.writing.iou_min) == (
        0.1, "hold", 0.5)  # fmt: skip
    assert safety.settle_attempts == 3 and safety.fence is not None
    assert not safety.fence.contains((0.7 + 0.3, 0.0, 1.0))  # beyond the 0.2 m margin


@pytest.mark.parametrize(
    ("section", "words"),
    [
        ("abort_policy: hover", "5: safety.abort_policy: Input should be 'hold' or 'land'"),
        ("deviation_bound_m: 0", "safety.deviation_bound_m: Input should be greater than 0"),
        ("iou_min: 1.5", "safety.iou_min"),
        ("deviaton_bound_m: 0.1", "5: safety.deviaton_bound_m: unknown field"),
    ],
)
def test_a_bad_safety_value_is_named_with_its_line(section: str, words: str) -> None:
    with pytest.raises(ShowError) as error:
        parse_show(BASE + "safety:\n  " + section + "\n")
    assert words in str(error.value)

"""showfile: the shipped shows load; bad shows are refused naming file, line and field."""

from __future__ import annotations

import itertools
import math
from pathlib import Path
from typing import Any

import pytest

from showfile import ShowFileError, dump_show, load_show, parse_show
from showfile.checks import footprint, polygons_overlap
from vehicles import ROOMS
from vehicles.registry import vehicle_kind

SHOWS = Path(__file__).resolve().parents[1] / "shows"

SOLO = """\
show_id: t
boards:
  - id: b1
    center_m_enu: [0, 0, 0.75]
    size_m: [1.4, 1.4]
    writing_area_m: [1.2, 1.2]
vehicles:
  - id: uav1
    board: b1
    home_m_enu: [0, -1.2, 0]
"""


def _problem(text: str) -> ShowFileError:
    with pytest.raises(ShowFileError) as info:
        parse_show(text, file="bad.yaml")
    return info.value


def test_airshow_has_four_quadrotors_over_four_boards_side_by_side() -> None:
    show = load_show(SHOWS / "airshow-2014.yaml")
    assert show.show_id == "airshow-2014"
    assert [v.kind for v in show.vehicles] == ["quadrotor-brush"] * 4
    assert sorted(v.board for v in show.vehicles) == sorted(b.id for b in show.boards)
    assert len(show.boards) == 4
    xs = sorted(b.center_m_enu[0] for b in show.boards)
    width = max(b.size_m[0] for b in show.boards)
    assert all(b.orientation == "horizontal" for b in show.boards)
    assert len({b.center_m_enu[1:] for b in show.boards}) == 1  # one row
    assert all(x1 - x0 >= width for x0, x1 in itertools.pairwise(xs))  # side by side
    assert show.zenoh.multicast_scouting is False
    assert show.source_path == SHOWS / "airshow-2014.yaml"


def test_solo_has_one_vehicle_and_defaults() -> None:
    show = load_show(SHOWS / "solo.yaml")
    assert [v.id for v in show.vehicles] == ["uav1"]
    assert show.time_scale == 1.0
    assert show.vehicle_limits("uav1") == show.limits


def test_dump_and_load_round_trip(tmp_path: Path) -> None:
    show = load_show(SHOWS / "airshow-2014.yaml")
    variant = show.model_copy(update={"time_scale": 20.0})
    dump_show(variant, tmp_path / "x.yaml")
    again = load_show(tmp_path / "x.yaml")
    assert again.model_copy(update={"source_path": None}) == variant.model_copy(
        update={"source_path": None}
    )
    assert again.time_scale == 20.0


def test_models_are_frozen() -> None:
    show = parse_show(SOLO)
    with pytest.raises(ValueError, match="frozen"):
        show.show_id = "other"  # type: ignore[misc]


def test_wrong_type_names_line_and_field() -> None:
    err = _problem(SOLO.replace("home_m_enu: [0, -1.2, 0]", "home_m_enu: [0, north, 0]"))
    assert err.file == "bad.yaml"
    assert err.line == 10
    assert err.field == "vehicles[0].home_m_enu[1]"
    assert "bad.yaml:10: vehicles[0].home_m_enu[1]" in str(err)


def test_unknown_field_is_refused_with_its_line() -> None:
    err = _problem(SOLO.replace("    board: b1\n", "    board: b1\n    colour: red\n"))
    assert (err.line, err.field) == (10, "vehicles[0].colour")
    assert "unknown field" in str(err)


def test_missing_field_points_at_its_block() -> None:
    err = _problem(SOLO.replace("    board: b1\n", ""))
    assert (err.line, err.field) == (8, "vehicles[0].board")
    assert "missing" in str(err)


def test_unknown_board_is_a_cross_check_error() -> None:
    err = _problem(SOLO.replace("board: b1", "board: b7"))
    assert (err.line, err.field) == (9, "vehicles[0].board")
    assert "unknown board 'b7'" in str(err)


def test_duplicate_ids_and_overlapping_boards() -> None:
    text = SOLO.replace(
        "vehicles:",
        "  - id: b1\n    center_m_enu: [1.0, 0.5, 0.75]\n    size_m: [1.4, 1.4]\n"
        "    writing_area_m: [1.2, 1.2]\nvehicles:",
    )
    err = _problem(text)
    fields = {p.field: p for p in err.problems}
    assert fields["boards[1].id"].line == 7
    assert "duplicate id 'b1'" in fields["boards[1].id"].message
    assert "overlaps board 'b1'" in fields["boards[1].center_m_enu"].message


def test_writing_area_must_fit_on_the_board() -> None:
    err = _problem(SOLO.replace("writing_area_m: [1.2, 1.2]", "writing_area_m: [1.2, 1.5]"))
    assert (err.line, err.field) == (6, "boards[0].writing_area_m[1]")


def test_mavlink_backend_needs_a_url_and_kind_needs_matching_board() -> None:
    err = _problem(SOLO.replace("    board: b1\n", "    board: b1\n    backend: mavlink\n"))
    assert err.field == "vehicles[0]" and "mavlink_url" in str(err)
    err = _problem(SOLO.replace("    board: b1\n", "    board: b1\n    kind: hexarotor-sponge\n"))
    assert "vertical board" in str(err)


def test_a_kind_without_a_room_is_refused_naming_the_kinds(monkeypatch: Any) -> None:
    monkeypatch.delitem(ROOMS, "quadrotor-brush")
    monkeypatch.delitem(ROOMS, "hexarotor-sponge")
    err = _problem(SOLO)
    fields = {p.field: p for p in err.problems}
    message = fields["vehicles[0].kind"].message
    assert "'quadrotor-brush'" in message and message.endswith("the kinds are: omni-wheel")


GROUND = """\
show_id: t
omni_wheel:
  steps: [{x_m: 1.5, height_m: 0.05}]
boards:
  - id: plaza
    orientation: floor
    center_m_enu: [3.5, 0, 0.05]
    size_m: [2.0, 2.0]
    writing_area_m: [1.8, 1.8]
vehicles:
  - id: ground1
    kind: omni-wheel
    board: plaza
    home_m_enu: [0, 0, 0]
"""


def test_a_ground_writer_reaches_its_floor_area_over_a_low_step() -> None:
    show = parse_show(GROUND)
    assert show.omni_wheel is not None and show.omni_wheel.steps[0].height_m == 0.05


@pytest.mark.parametrize(
    ("change", "words"),
    [
        (("0.05}]\nboards", "0.3}]\nboards"), "the step at x=1.50 m is 0.300 m high"),
        (("[3.5, 0, 0.05]", "[3.5, 0, 0.0]"), "the floor there is 0.050 m high"),
        (("[3.5, 0, 0.05]", "[1.5, 0, 0.05]"), "straddles the step edge at x=1.50 m"),
        (("[3.5, 0, 0.05]", "[70, 0, 0.05]"), "out of reach: 70.0 m of route"),
    ],
)
def test_a_floor_area_the_ground_writer_cannot_reach_is_refused_in_one_line(
    change: tuple[str, str], words: str
) -> None:
    text = GROUND.replace(*change)
    if "0.3}" in text:
        text = text.replace("[3.5, 0, 0.05]", "[3.5, 0, 0.3]")
    err = _problem(text)
    problem = {p.field: p for p in err.problems}["vehicles[0].board"]
    assert words in problem.message and "'plaza'" in problem.message
    assert "\n" not in str(problem) and "bad.yaml" in str(problem)


MAVLINK_SOLO = SOLO.replace(
    "    board: b1\n",
    "    board: b1\n    backend: mavlink\n    mavlink_url: udp:127.0.0.1:14561\n",
)


def test_mavlink_settings_are_typed_fields_with_defaults() -> None:
    vehicle = parse_show(MAVLINK_SOLO).vehicles[0]
    assert vehicle.mavlink_origin_m_enu is None
    assert (vehicle.mavlink_setpoint_rate_hz, vehicle.mavlink_mocap) == (50.0, "none")
    text = MAVLINK_SOLO.replace(
        "    board: b1\n",
        "    board: b1\n    mavlink_origin_m_enu: [1, 2, 0]\n"
        "    mavlink_setpoint_rate_hz: 100\n    mavlink_mocap: vision_position_estimate\n",
    )
    vehicle = parse_show(text).vehicles[0]
    assert vehicle.mavlink_origin_m_enu == (1.0, 2.0, 0.0)
    assert vehicle.mavlink_mocap == "vision_position_estimate"
    # attitude setpoints were removed (they diverged on ArduCopter SITL): an old show file says so
    err = _problem(
        MAVLINK_SOLO.replace("    board: b1\n", "    board: b1\n    mavlink_setpoints: attitude\n")
    )
    assert (err.line, err.field) == (10, "vehicles[0].mavlink_setpoints")
    err = _problem(
        MAVLINK_SOLO.replace(
            "    board: b1\n", "    board: b1\n    mavlink_setpoint_rate_hz: 150\n"
        )
        + "controller: {rate_hz: 100}\n"
    )
    assert (err.line, err.field) == (10, "vehicles[0].mavlink_setpoint_rate_hz")
    assert "exceeds the control rate" in str(err)


def test_mavlink_sim_flag_needs_mavlink_vehicles_and_kiosk_text_length_is_bounded() -> None:
    assert not parse_show(SOLO).mavlink_sim.enabled
    assert parse_show(MAVLINK_SOLO + "mavlink_sim: {enabled: true}\n").mavlink_sim.enabled
    err = _problem(SOLO + "mavlink_sim: {enabled: true}\n")
    assert err.field == "mavlink_sim.enabled" and "backend: mavlink" in str(err)
    assert parse_show(SOLO).kiosk.max_text_chars == 1
    assert parse_show(SOLO + "kiosk: {max_text_chars: 8}\n").kiosk.max_text_chars == 8
    assert _problem(SOLO + "kiosk: {max_text_chars: 0}\n").field == "kiosk.max_text_chars"


def test_the_kiosks_body_limit_holds_its_most_points_and_fits_a_bus_request() -> None:
    err = _problem(SOLO + "kiosk: {max_payload_bytes: 200000, max_points: 5000}\n")
    assert err.field == "kiosk" and "cannot carry max_points 5000" in str(err)
    assert "bad.yaml:11: kiosk:" in str(err) and "(242000 bytes)" in str(err)
    err = _problem(SOLO + "kiosk: {max_payload_bytes: 300000}\n")
    assert err.field == "kiosk.max_payload_bytes"
    assert parse_show(SOLO + "kiosk: {max_payload_bytes: 100000, max_points: 2000}\n")


def test_shipped_shows_fly_the_default_controller_and_the_rehearsal_simulates_its_vehicles() -> (
    None
):
    shows = {path.stem: load_show(path) for path in SHOWS.glob("*.yaml")}
    assert {name: s.controller.preset for name, s in shows.items()} == dict.fromkeys(
        shows, "default"
    )
    rehearsal = shows["rehearsal-mavlink"]
    assert rehearsal.mavlink_sim.enabled
    assert all(v.backend == "mavlink" for v in rehearsal.vehicles)


def test_yaml_syntax_and_duplicate_keys() -> None:
    err = _problem(SOLO.replace("  - id: uav1", "  - id: [uav1"))
    assert err.line is not None and err.line >= 8 and "YAML syntax" in str(err)
    err = _problem(SOLO + "show_id: again\n")
    assert (err.line, err.field) == (11, "show_id")


def test_unreadable_file_names_it(tmp_path: Path) -> None:
    with pytest.raises(ShowFileError, match=r"nope\.yaml"):
        load_show(tmp_path / "nope.yaml")


@pytest.mark.parametrize("named", ["absolute", "relative"])
def test_relative_paths_start_from_the_show_files_folder_not_the_working_directory(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, named: str
) -> None:
    """Issue 31: ``skyquill status /abs/show.yaml`` run from another folder looked for the keys
    there. Whether the file is named absolute or relative to the working directory, its paths
    start from its own folder; the keys' default folder is beside the database."""
    root = tmp_path.resolve()
    (root / "shows").mkdir()
    (root / "elsewhere").mkdir()
    storage = "storage: {database: ../out/t/show.sqlite3, recordings_dir: rec}\n"
    (root / "shows" / "t.yaml").write_text(SOLO + storage, encoding="utf-8")
    (root / "shows" / "k.yaml").write_text(SOLO + "security: {keys_dir: k}\n", encoding="utf-8")
    monkeypatch.chdir(root / "elsewhere")
    folder = root / "shows" if named == "absolute" else Path("..") / "shows"
    show = load_show(folder / "t.yaml")
    assert show.database_path == root / "out" / "t" / "show.sqlite3"
    assert show.keys_dir == root / "out" / "t" / "keys"
    assert show.recordings_dir == root / "shows" / "rec"
    defaults = load_show(folder / "k.yaml")
    assert defaults.keys_dir == root / "shows" / "k"
    assert defaults.database_path == root / "shows" / "out" / "t" / "show.sqlite3"
    assert defaults.recordings_dir == root / "shows" / "out" / "t" / "recordings"


def test_a_show_built_in_memory_keeps_its_paths_relative_to_the_working_directory() -> None:
    show = parse_show(SOLO)
    assert show.database_path == Path("out/t/show.sqlite3")
    assert show.keys_dir == Path("out/t/keys")
    assert show.recordings_dir == Path("out/t/recordings")


def test_rotated_rectangles_overlap_by_separating_axes() -> None:
    show = parse_show(SOLO)
    board = show.boards[0]
    moved = board.model_copy(update={"center_m_enu": (1.5, 0.0, 0.75)})
    assert not polygons_overlap(footprint(board), footprint(moved))
    # at 45 degrees the corner reaches 1.4 / sqrt(2) ~ 0.99 m from the centre
    turned = moved.model_copy(update={"yaw_deg": 45.0})
    assert polygons_overlap(footprint(board), footprint(turned))
    assert math.isclose(max(x for x, _ in footprint(board)), 0.7)


def test_a_wall_whose_writing_area_reaches_beyond_the_hexarotor_is_refused_in_one_line() -> None:
    text = (SHOWS / "flying-calligrapher.yaml").read_text(encoding="utf-8")
    wide = text.replace(
        "size_m: [2.0, 1.5], writing_area_m: [0.5, 0.5]",
        "size_m: [4.0, 1.5], writing_area_m: [3.9, 1.4]",
    )
    err = _problem(wide)
    problem = {p.field: p for p in err.problems}["vehicles[0].board"]
    assert "'wall'" in problem.message and "beyond the reach 1.5 m" in problem.message
    longer = wide.replace("force_rate_max_nps: 2.0", "force_rate_max_nps: 2.0\n  reach_m: 2.5")
    hexarotor = parse_show(longer).hexarotor
    assert hexarotor is not None and hexarotor.reach_m == 2.5


def test_only_kinds_with_an_autopilot_world_may_fly_behind_mavlink() -> None:
    for name in ROOMS:
        kind = vehicle_kind(name)
        has_world = kind.autopilot_world(kind.settings(None, None)) is not None
        assert has_world == ROOMS[name].autopilot, name
    text = (SHOWS / "flying-calligrapher.yaml").read_text(encoding="utf-8")
    mavlink = "backend: mavlink, mavlink_url: 'udp:127.0.0.1:14561'"
    err = _problem(text.replace("backend: sim", mavlink))
    message = {p.field: p for p in err.problems}["vehicles[0].backend"].message
    assert message.startswith("a hexarotor-sponge cannot fly behind an autopilot yet")

"""Cross-checks of a show that one field alone cannot express (pure).

Each problem is returned with the path of the field at fault (``("vehicles", 2, "board")``) so the
loader can name the file line. What is a kind's own (the surface it writes on, whether an
autopilot flies it, how far it reaches) is asked of its room's record, ``vehicles.ROOMS``, and of
the room's light show checks.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable, Iterator
from typing import cast

from showfile.models import Board, Show, Vehicle
from showfile.security import on_loopback
from vehicles import ROOMS

Loc = tuple[str | int, ...]
Problem = tuple[Loc, str]

_VERTICAL_DEPTH_M = 0.05
"""Plan-view depth assumed for a vertical board (a wall panel)."""


def footprint(board: Board) -> list[tuple[float, float]]:
    """Corners of the board's plan-view rectangle in world x/y [m], counter-clockwise."""
    width, depth = board.size_m
    if board.orientation == "vertical":
        depth = _VERTICAL_DEPTH_M
    c, s = math.cos(board.yaw_rad), math.sin(board.yaw_rad)
    cx, cy = board.center_m_enu[0], board.center_m_enu[1]
    corners = [(-width / 2, -depth / 2), (width / 2, -depth / 2), (width / 2, depth / 2)]
    corners.append((-width / 2, depth / 2))
    return [(cx + c * x - s * y, cy + s * x + c * y) for x, y in corners]


def _axes(poly: list[tuple[float, float]]) -> Iterator[tuple[float, float]]:
    for i, (x0, y0) in enumerate(poly):
        x1, y1 = poly[(i + 1) % len(poly)]
        yield (y0 - y1, x1 - x0)


def _project(poly: list[tuple[float, float]], axis: tuple[float, float]) -> tuple[float, float]:
    values = [x * axis[0] + y * axis[1] for x, y in poly]
    return min(values), max(values)


def polygons_overlap(a: list[tuple[float, float]], b: list[tuple[float, float]]) -> bool:
    """Separating-axis test for two convex polygons; touching edges do not overlap."""
    for axis in [*_axes(a), *_axes(b)]:
        a_lo, a_hi = _project(a, axis)
        b_lo, b_hi = _project(b, axis)
        scale = math.hypot(*axis)
        if a_hi <= b_lo + 1e-9 * scale or b_hi <= a_lo + 1e-9 * scale:
            return False
    return True


def _boards_overlap(a: Board, b: Board) -> bool:
    if not polygons_overlap(footprint(a), footprint(b)):
        return False
    if a.orientation == b.orientation == "vertical":  # walls may be stacked at other heights
        half_a, half_b = a.size_m[1] / 2, b.size_m[1] / 2
        return abs(a.center_m_enu[2] - b.center_m_enu[2]) < half_a + half_b - 1e-9
    return True


def _duplicates(ids: list[str], section: str) -> Iterator[Problem]:
    seen: set[str] = set()
    for index, item_id in enumerate(ids):
        if item_id in seen:
            yield (section, index, "id"), f"duplicate id {item_id!r}"
        seen.add(item_id)


def cross_check(show: Show) -> list[Problem]:
    """Every problem of the show that single fields cannot catch; empty when the show is sound."""
    problems: list[Problem] = []
    problems += _duplicates([b.id for b in show.boards], "boards")
    problems += _duplicates([v.id for v in show.vehicles], "vehicles")
    for i, board in enumerate(show.boards):
        for axis, (area, size) in enumerate(zip(board.writing_area_m, board.size_m, strict=True)):
            if area > size + 1e-9:
                problems.append(
                    (
                        ("boards", i, "writing_area_m", axis),
                        f"writing area {area} m exceeds the board size {size} m",
                    )
                )
        for j in range(i):
            if _boards_overlap(board, show.boards[j]):
                problems.append(
                    (("boards", i, "center_m_enu"), f"overlaps board {show.boards[j].id!r}")
                )
    board_ids = {b.id: b for b in show.boards}
    for i, vehicle in enumerate(show.vehicles):  # every kind has a room (Vehicle.kind)
        surface = ROOMS[vehicle.kind].orientation
        target = board_ids.get(vehicle.board)
        if target is None:
            problems.append(
                (
                    ("vehicles", i, "board"),
                    f"unknown board {vehicle.board!r}; boards: {sorted(board_ids)}",
                )
            )
        elif surface != target.orientation:
            problems.append(
                (
                    ("vehicles", i, "board"),
                    f"a {vehicle.kind} writes on a {surface} board, "
                    f"but board {target.id!r} is {target.orientation}",
                )
            )
        else:
            why = reach_problem(show, vehicle)
            if why is not None:
                problems.append((("vehicles", i, "board"), why))
        problems += _homes_overlap(show, i)
    problems += _mavlink_problems(show)
    problems += _unsecured_listen(show)
    if show.zenoh.multicast_scouting is False and not show.zenoh.connect:
        problems.append((("zenoh", "connect"), "no connect endpoint and multicast scouting off"))
    return problems


def _homes_overlap(show: Show, i: int) -> list[Problem]:
    """Vehicle ``i``'s home closer to an earlier vehicle's than their footprints allow (each
    kind's ``footprint_radius_m``: the two would touch standing at their homes)."""
    vehicle, radius_m = show.vehicles[i], ROOMS[show.vehicles[i].kind].footprint_radius_m
    problems: list[Problem] = []
    for neighbour in show.vehicles[:i]:
        need_m = radius_m + ROOMS[neighbour.kind].footprint_radius_m
        distance_m = math.dist(vehicle.home_m_enu, neighbour.home_m_enu)
        if distance_m < need_m:
            problems.append(
                (
                    ("vehicles", i, "home_m_enu"),
                    f"{distance_m:.2f} m from the home of {neighbour.id!r}: their footprints "
                    f"need {need_m:.2f} m ({vehicle.kind} {radius_m:.2f} m, "
                    f"{neighbour.kind} {need_m - radius_m:.2f} m)",
                )
            )
    return problems


def _unsecured_listen(show: Show) -> list[Problem]:
    """With ``security: none`` every listen endpoint of the bus on loopback: anyone who reaches
    a plain bus may command the fleet."""
    if show.security.mode != "none":
        return []
    listening: list[tuple[Loc, tuple[str, ...]]] = [
        (("zenoh", "router_listen"), show.zenoh.router_listen),
        (("zenoh", "peer_listen"), show.zenoh.peer_listen),
    ]
    for name, host in show.zenoh.hosts.items():
        listening.append((("zenoh", "hosts", name, "router_listen"), host.router_listen))
    return [
        (
            (*loc, i),
            f"{endpoint} reaches beyond this machine and security is none (anyone there could "
            f"command the fleet): listen on 127.0.0.1 or use security: mtls",
        )
        for loc, endpoints in listening
        for i, endpoint in enumerate(endpoints)
        if not on_loopback(endpoint)
    ]


def _mavlink_problems(show: Show) -> list[Problem]:
    """MAVLink settings that only make sense together with the rest of the show."""
    problems: list[Problem] = []
    mavlink = [i for i, v in enumerate(show.vehicles) if v.backend == "mavlink"]
    for i in mavlink:
        kind = show.vehicles[i].kind
        if not ROOMS[kind].autopilot:
            autopilot_kinds = sorted(name for name, room in ROOMS.items() if room.autopilot)
            problems.append(
                (
                    ("vehicles", i, "backend"),
                    f"a {kind} cannot fly behind an autopilot yet: use backend: sim "
                    f"(autopilot kinds: {', '.join(autopilot_kinds)})",
                )
            )
        rate_hz = show.vehicles[i].mavlink_setpoint_rate_hz
        if rate_hz > show.controller.rate_hz:
            problems.append(
                (
                    ("vehicles", i, "mavlink_setpoint_rate_hz"),
                    f"{rate_hz} Hz exceeds the control rate {show.controller.rate_hz} Hz",
                )
            )
    if show.mavlink_sim.enabled and not mavlink:
        problems.append((("mavlink_sim", "enabled"), "no vehicle has backend: mavlink"))
    return problems


BoardCheck = Callable[[Show, Vehicle, Board], str | None]
"""A room's ``board_problem(show, vehicle, board)`` (``Room.show_checks``): why the vehicle cannot
write on its board, in one line, or None."""


def _board_check(kind: str) -> BoardCheck | None:
    """The light show check of ``kind``'s room, imported on first use; None when it has none."""
    module = ROOMS[kind].show_checks
    if module is None:
        return None
    return cast(BoardCheck, importlib.import_module(module).board_problem)


def reach_problem(show: Show, vehicle: Vehicle) -> str | None:
    """Why ``vehicle`` cannot reach its board from its home or write all of it, asked of its
    kind's room (a floor area behind a step higher than a ground writer climbs, off the terrain,
    straddling a step, at the wrong height, too far; a wall whose writing area reaches beyond the
    hexarotor's ``reach_m``), in one line naming the board; None when it can."""
    check = _board_check(vehicle.kind)
    return None if check is None else check(show, vehicle, show.board(vehicle.board))


def cannot_write(show: Show, vehicle: Vehicle) -> str | None:
    """Why ``vehicle`` can write no job of ``show``, in one line (its kind does not write on its
    board's surface, or it cannot reach the board: :func:`reach_problem`); None when it can."""
    board = show.board(vehicle.board)
    surface = ROOMS[vehicle.kind].orientation
    if surface != board.orientation:
        return (
            f"a {vehicle.kind} writes on a {surface} board, not on {board.orientation} {board.id!r}"
        )
    return reach_problem(show, vehicle)

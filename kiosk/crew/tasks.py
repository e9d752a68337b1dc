"""What the crew has to do, from the orchestrator's fleet snapshot (pure): each board waiting
for a fresh sheet (``ShowSnapshot.dirty_boards``) and each vehicle waiting for a battery swap
(``VehicleSummary.state == "battery_swap"``), as the page lists them."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Literal

from bus.messages import ShowSnapshot

CrewCommand = Literal["fresh_sheet", "battery_swapped"]
COMMANDS: tuple[CrewCommand, ...] = ("fresh_sheet", "battery_swapped")
"""The only commands the crew page sends (the orchestrator refuses any other from the crew)."""


@dataclass(frozen=True)
class CrewTask:
    """One thing for the crew to do and confirm."""

    command: CrewCommand
    """What the crew's tap confirms."""
    target: str
    """The board (``fresh_sheet``) or the vehicle (``battery_swapped``)."""
    board_id: str | None
    """The board it is at (None: a vehicle without one)."""
    place: int | None
    """Position of that board from the left, 1 first (None: unknown)."""
    battery_percent: int | None = None
    """``battery_swapped``: the charge its vehicle last reported, [%]."""

    @property
    def key(self) -> tuple[str, str]:
        return self.command, self.target

    def to_json(self, confirmed: bool) -> dict[str, object]:
        return {
            "command": self.command,
            "target": self.target,
            "board": self.board_id,
            "place": self.place,
            "percent": self.battery_percent,
            "confirmed": confirmed,
        }


def crew_tasks(snapshot: ShowSnapshot, places: Mapping[str, int]) -> list[CrewTask]:
    """Boards waiting for a sheet, then vehicles waiting for a battery, each by board position;
    ``places``: vehicle id -> position of its board from the left."""
    board_place = {v.board_id: places.get(v.vehicle_id) for v in snapshot.vehicles if v.board_id}
    sheets = [
        CrewTask("fresh_sheet", board, board, board_place.get(board))
        for board in snapshot.dirty_boards
    ]
    batteries = [
        CrewTask(
            "battery_swapped",
            v.vehicle_id,
            v.board_id,
            places.get(v.vehicle_id),
            None if v.battery_fraction is None else round(100 * v.battery_fraction),
        )
        for v in snapshot.vehicles
        if v.state == "battery_swap"
    ]
    return _in_order(sheets) + _in_order(batteries)


def _in_order(tasks: Iterable[CrewTask]) -> list[CrewTask]:
    return sorted(tasks, key=lambda t: (t.place is None, t.place or 0, t.target))

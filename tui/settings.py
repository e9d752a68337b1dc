"""What the console needs from the show file, as small frozen values (tests build them directly)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

from showfile import Board, Show
from tui.venue import Venue, venue_from_show

BoardOrientation = Literal["horizontal", "vertical"]


@dataclass(frozen=True)
class BoardGeometry:
    """Where a board is, to draw paths in the board's own frame."""

    board_id: str
    """Board identifier from the show file."""
    center_m_enu: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """Centre of the board in the world frame, in [m]."""
    yaw_deg: float = 0.0
    """Rotation of the board's x axis from world east, about up, in [deg]."""
    size_m: tuple[float, float] = (1.4, 1.4)
    """Board width and height in [m]."""
    writing_area_m: tuple[float, float] = (1.2, 1.2)
    """Width and height of the area characters are laid out in, centred on the board, in [m]."""
    orientation: BoardOrientation = "horizontal"
    """``horizontal`` (a table below the vehicle: picture x, y = board x, y) or ``vertical`` (a
    wall: picture x = board x, picture y = up)."""

    def to_board(self, position_m_enu: tuple[float, float, float]) -> tuple[float, float]:
        """A world point in the board frame ``(u, v)`` in [m]; v points up on the picture."""
        dx = position_m_enu[0] - self.center_m_enu[0]
        dy = position_m_enu[1] - self.center_m_enu[1]
        yaw = math.radians(self.yaw_deg)
        c, s = math.cos(yaw), math.sin(yaw)
        u = c * dx + s * dy
        if self.orientation == "vertical":
            return u, position_m_enu[2] - self.center_m_enu[2]
        return u, -s * dx + c * dy


@dataclass(frozen=True)
class VehicleSpec:
    """A vehicle listed in the show file (shown before it ever appears on the bus)."""

    vehicle_id: str
    """Vehicle identifier."""
    kind: str
    """Vehicle kind, e.g. ``quadrotor-brush``."""
    board_id: str | None = None
    """Board it writes on."""
    surface: str = ""
    """What that board is: ``board`` (a table), ``wall`` or ``floor``; empty if unknown."""


@dataclass(frozen=True)
class ConsoleSettings:
    """Everything the console takes from a show file."""

    show_id: str
    """Show identifier (the Zenoh namespace)."""
    boards: tuple[BoardGeometry, ...] = ()
    """Boards, in show-file order."""
    vehicles: tuple[VehicleSpec, ...] = ()
    """Vehicles, in show-file order."""
    venue: Venue = field(default_factory=Venue)
    """The plan view of every board, home and geofence (the console's venue plan)."""
    tracking_error_alert_m: float = 0.05
    """Tracking error above which a writing vehicle raises an alert, in [m]."""
    lost_after_s: float = 1.5
    """Telemetry older than this is shown as stale, in [s]."""
    force_error_alert_n: float = 1.0
    """A writing vehicle's contact force further than this from its target is shown reversed
    red, in [N] (a sixth of the sponge pen's calibrated 1-6 N range)."""
    redraw_hz: float = 20.0
    """Highest redraw rate of the live views, in [Hz] (10-30 is sensible)."""
    command_timeout_s: float = 3.0
    """How long to wait for the orchestrator's answer to a command, in [s]."""

    def board(self, board_id: str | None) -> BoardGeometry | None:
        for board in self.boards:
            if board.board_id == board_id:
                return board
        return None


def board_geometry(board: Board) -> BoardGeometry:
    """The drawing geometry of a show-file board (a floor is drawn like a table)."""
    return BoardGeometry(
        board_id=board.id,
        center_m_enu=board.center_m_enu,
        yaw_deg=board.yaw_deg,
        size_m=board.size_m,
        writing_area_m=board.writing_area_m,
        orientation="vertical" if board.orientation == "vertical" else "horizontal",
    )


def settings_from_show(show: Show, *, redraw_hz: float = 20.0) -> ConsoleSettings:
    """Console settings from a loaded show (:func:`showfile.load_show`)."""
    return ConsoleSettings(
        show_id=show.show_id,
        boards=tuple(board_geometry(b) for b in show.boards),
        vehicles=tuple(
            VehicleSpec(v.id, v.kind, v.board, _surface(show, v.board)) for v in show.vehicles
        ),
        venue=venue_from_show(show),
        tracking_error_alert_m=show.policy.tracking_error_alert_m,
        lost_after_s=show.policy.lost_after_s,
        redraw_hz=redraw_hz,
    )


SURFACE_NAMES = {"horizontal": "board", "vertical": "wall", "floor": "floor"}
"""What the console calls each board orientation of the show file."""


def _surface(show: Show, board_id: str | None) -> str:
    for board in show.boards:
        if board.id == board_id:
            return SURFACE_NAMES.get(board.orientation, board.orientation)
    return ""

"""The kiosk's settings: one typed object, built from the show file or by tests."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

from kiosk.limits import SubmissionLimits
from kiosk.wording import board_numbers
from planner.pipeline import BoardFrame, PlanOptions
from showfile.planning import plan_options
from vehicles.registry import vehicle_kind

BRUSH_KIND = "quadrotor-brush"
"""The kind whose planner options the kiosk's settings carry (:attr:`KioskSettings.plan`)."""


@dataclass(frozen=True)
class KioskSettings:
    """Everything the kiosk service needs besides the bus session."""

    show_id: str
    """Show identifier (the bus namespace)."""
    host: str = "127.0.0.1"
    """Address the web server listens on."""
    port: int = 8765
    """TCP port of the web server (0: any free port)."""
    limits: SubmissionLimits = field(default_factory=SubmissionLimits)
    """Bounds on one submission and the blocklist."""
    rate_limit_per_minute: int = 6
    """Submissions per minute per client address, whatever its cookies (see kiosk.addresses)."""
    preview_rate_per_minute: int = 60
    """Previews per minute per client address (each runs the planner)."""
    trusted_proxies: tuple[str, ...] = ()
    """Reverse proxies (addresses or networks) whose ``X-Forwarded-For`` names the client; none
    by default, so the header is ignored."""
    writing_area_m: tuple[float, float] = (1.2, 1.2)
    """Width and height of the writing area the preview fits the glyph into, in [m]."""
    margin_m: float = 0.05
    """Free border kept inside the writing area, in [m]."""
    plan: PlanOptions = field(default_factory=PlanOptions)
    """Planner options of the preview (the board is the writing area's own frame)."""
    submit_timeout_s: float = 5.0
    """How long to wait for the orchestrator's answer to a submission, in [s]."""
    secure_cookie: bool = False
    """Mark the session cookie Secure (when served over HTTPS behind a proxy)."""
    places: dict[str, int] = field(default_factory=dict)
    """Vehicle id -> position of its board from the left (1 first); the page words it."""
    max_pending: int = 200
    """Submissions waiting for the orchestrator's first answer at once; beyond, new ones are
    refused before they are sent."""
    max_flight_s: float = 90.0
    """Longest planned flight of one character, [s]; longer previews and submissions are refused."""
    idle_reset_s: float = 60.0
    """The page goes back to the start after this long without a touch, [s] (0: never)."""
    stale_after_s: float = 2.0
    """The status is stale when the orchestrator's 1 Hz fleet snapshot is older than this, [s]."""
    preview_kind: str = "quadrotor-brush"
    """The vehicle kind the preview plans for: the kind writing on the first board."""
    width_range_m: tuple[float, float] | None = None
    """Narrowest and widest line in [m] of the preview kind's pen, for kinds that write with a
    width (the drawing pad then sends a width per point); None for a brush of fixed width."""
    preview_kind_settings: Any = None
    """The preview kind's settings (``VehicleKind.settings``) for the first board's vehicle, for
    kinds other than the brush (whose planner options are :attr:`plan`); None: the kind's
    defaults."""


def settings_from_show(show: Any, *, port: int | None = None) -> KioskSettings:
    """Kiosk settings from a loaded show (``showfile.Show``); ``port`` overrides the file's.

    The preview is planned on the first board's writing area for the kind of the vehicles on it,
    with the show's limits and planning settings (every vehicle re-plans its job on its own
    board).
    """
    kiosk, board, planning = show.kiosk, show.boards[0], show.planning
    limits = SubmissionLimits(
        max_payload_bytes=kiosk.max_payload_bytes,
        max_strokes=kiosk.max_strokes,
        max_points=kiosk.max_points,
        max_text_chars=kiosk.max_text_chars,
        blocklist=tuple(kiosk.blocklist),
    )
    frame = BoardFrame(center_m_enu=(0.0, 0.0, 0.0))
    plan = plan_options(planning, show.limits, frame)
    plan = replace(plan, clearance_m=max(planning.clearance_m, 1e-3))
    width_m, height_m = board.writing_area_m
    writer = next((v for v in show.vehicles if v.board == board.id), None)
    kind = BRUSH_KIND if writer is None else writer.kind
    preview_settings = (
        None if writer is None or kind == BRUSH_KIND else kind_settings(show, writer.id, kind)
    )
    widths_m = (
        None if preview_settings is None else vehicle_kind(kind).width_range_m(preview_settings)
    )
    return KioskSettings(
        show_id=show.show_id,
        host=kiosk.host,
        port=kiosk.port if port is None else port,
        limits=limits,
        rate_limit_per_minute=kiosk.rate_limit_per_minute,
        trusted_proxies=tuple(str(network) for network in kiosk.trusted_proxies),
        writing_area_m=(float(width_m), float(height_m)),
        margin_m=min(planning.margin_m, 0.45 * min(width_m, height_m)),
        plan=plan,
        max_flight_s=kiosk.max_flight_s,
        idle_reset_s=kiosk.idle_reset_s,
        places=board_numbers(
            {vehicle.id: vehicle.board for vehicle in show.vehicles},
            [b.id for b in show.boards],
        ),
        preview_kind=kind,
        width_range_m=widths_m,
        preview_kind_settings=preview_settings,
    )


def kind_settings(show: Any, vehicle_id: str, kind: str) -> Any:
    """The settings ``kind`` gives ``vehicle_id`` of ``show`` (its pen, its limits)."""
    return vehicle_kind(kind).settings(show, vehicle_id)

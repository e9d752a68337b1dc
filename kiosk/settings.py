"""The kiosk's settings: one typed object, built from the show file or by tests."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from kiosk.limits import SubmissionLimits
from kiosk.wording import board_numbers
from vehicles import DEFAULT_KIND
from vehicles.jobs import JobSetup, job_setup, kind_writers
from vehicles.registry import vehicle_kind
from vehicles.surface import Surface

PATH_RATE_HZ = 100.0
"""Rate at which a preview's planned trajectory is sampled before decimation, [Hz] (the show's
``planning.sample_rate_hz`` for the preview: the page gets a few hundred points)."""


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
    """Width and height in [m] of the first board's writing area (the page's), and of the area
    a preview without :attr:`preview_kinds` is planned on."""
    margin_m: float = 0.05
    """Free border in [m] kept inside the writing area by a preview without
    :attr:`preview_kinds`."""
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
    width_range_m: tuple[float, float] | None = None
    """Narrowest and widest line in [m] a visitor may draw: the span of the pens of the kinds
    that write with a width (the drawing pad then sends a width per point); None where every
    kind writes one width."""
    preview_kinds: tuple[JobSetup, ...] = ()
    """Each kind of the show as the orchestrator plans for it (``vehicles.jobs``: the settings,
    board and margin of the vehicle standing for the kind), in the order of their first board,
    sampled at :data:`PATH_RATE_HZ`; the preview shows the first whose planner accepts the
    submission. Empty (a kiosk without a show): ``vehicles.DEFAULT_KIND`` alone
    (:func:`kind_preview` on :attr:`writing_area_m`)."""

    crew_phones: Path | None = None
    """The crew's paired phones and open pairing codes (``kiosk/crew/pairing.py``; the show's
    ``<keys_dir>/crew-phones.json``); None: no crew page."""

    def kinds(self) -> tuple[JobSetup, ...]:
        """The kinds the preview plans for, first choice first."""
        if self.preview_kinds:
            return self.preview_kinds
        return (kind_preview(DEFAULT_KIND, self.writing_area_m, self.margin_m),)


def kind_preview(name: str, writing_area_m: tuple[float, float], margin_m: float) -> JobSetup:
    """How a kiosk without a show previews for kind ``name``: its default settings
    (``VehicleKind.settings(None, None)``) on a writing area ``writing_area_m`` in [m] centred at
    the origin, ``margin_m`` in [m] kept free inside it."""
    kind = vehicle_kind(name)
    area = Surface.of(kind.orientation, (0.0, 0.0, 0.0), 0.0)
    return JobSetup(kind, kind.settings(None, None), area, writing_area_m, margin_m)


def settings_from_show(show: Any, *, port: int | None = None) -> KioskSettings:
    """Kiosk settings from a loaded show (``showfile.Show``); ``port`` overrides the file's.

    The preview plans for every kind of the show as the orchestrator does (each kind's first
    vehicle in board order, its settings, its board; ``vehicles.jobs``), only sampled at
    :data:`PATH_RATE_HZ`.
    """
    kiosk, board, planning = show.kiosk, show.boards[0], show.planning
    limits = SubmissionLimits(
        max_payload_bytes=kiosk.max_payload_bytes,
        max_strokes=kiosk.max_strokes,
        max_points=kiosk.max_points,
        max_text_chars=kiosk.max_text_chars,
        blocklist=tuple(kiosk.blocklist),
        max_phrase_chars=len(show.boards),  # the row, as the orchestrator counts it
    )
    # every kind reads its settings from the show as for its vehicles; the preview's sample
    # rate goes the same way, through the planning section (the brush samples its plan at it)
    sampled = show.model_copy(
        update={"planning": planning.model_copy(update={"sample_rate_hz": PATH_RATE_HZ})}
    )
    kinds = tuple(job_setup(sampled, vehicle_id) for vehicle_id in kind_writers(show).values())
    width_m, height_m = board.writing_area_m
    return KioskSettings(
        show_id=show.show_id,
        host=kiosk.host,
        port=kiosk.port if port is None else port,
        limits=limits,
        rate_limit_per_minute=kiosk.rate_limit_per_minute,
        trusted_proxies=tuple(str(network) for network in kiosk.trusted_proxies),
        writing_area_m=(float(width_m), float(height_m)),
        margin_m=planning.margin_m,
        max_flight_s=kiosk.max_flight_s,
        idle_reset_s=kiosk.idle_reset_s,
        places=board_numbers(
            {vehicle.id: vehicle.board for vehicle in show.vehicles},
            [b.id for b in show.boards],
        ),
        width_range_m=width_span_m(kinds),
        preview_kinds=kinds,
        crew_phones=crew_phones_path(show.keys_dir),
    )


def crew_phones_path(keys_dir: Path) -> Path:
    """Where a show keeps its crew's phones (beside its keys: as secret)."""
    return Path(keys_dir) / "crew-phones.json"


def width_span_m(kinds: tuple[JobSetup, ...]) -> tuple[float, float] | None:
    """The widths in [m] the kinds that write with a width draw, from the narrowest to the
    widest (the union of their ranges, as the one interval the drawing pad takes); None where
    every kind writes one width."""
    ranges = [r for k in kinds if (r := k.kind.width_range_m(k.settings)) is not None]
    if not ranges:
        return None
    return min(low for low, _ in ranges), max(high for _, high in ranges)

"""The show file's sections for its services rather than its vehicles: ``zenoh`` (endpoints and
hosts), ``storage`` (the orchestrator's durable state), ``policy`` (moderation and queue) and
``kiosk`` (the public web page)."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any, Literal

from pydantic import Field, field_validator, model_validator
from pydantic.networks import IPvAnyNetwork

from showfile.model_base import ID_PATTERN, Identifier, ShowModel


class ZenohHost(ShowModel):
    """One machine of a show that spans several (a ground station, companion computers): its own
    router, linked to the ground station's, and the processes that run on it."""

    router_listen: tuple[str, ...] = Field(min_length=1)
    """Endpoints this host's router listens on (those its own processes and, on the ground
    station, the companion routers reach it at)."""
    connect: tuple[str, ...] = ()
    """Endpoints this host's processes connect to (default: its router's first endpoint)."""
    router_connect: tuple[str, ...] = ()
    """The ground station router's endpoints as this host reaches them (a companion host)."""
    services: bool = False
    """The ground station: the orchestrator, the kiosk and the operators' clients run here."""
    vehicles: tuple[Identifier, ...] = ()
    """The vehicles whose agents run on this host (each vehicle on exactly one host)."""

    @property
    def local_connect(self) -> tuple[str, ...]:
        """Where this host's processes reach its router."""
        return self.connect or self.router_listen[:1]


class ZenohSettings(ShowModel):
    """How processes of the show find each other (explicit endpoints; see bus/session.py)."""

    router_listen: tuple[str, ...] = ("tcp/127.0.0.1:7447",)
    """Endpoints the show's router listens on."""
    connect: tuple[str, ...] = ("tcp/127.0.0.1:7447",)
    """Endpoints clients and peers connect to (the router, as seen from them)."""
    multicast_scouting: bool = False
    """Discover other processes by UDP multicast; off so that only explicit endpoints are used."""
    router_connect: tuple[str, ...] = ()
    """Other routers the show's router links to (ground station <-> companion computers)."""
    peer_listen: tuple[str, ...] = ()
    """Endpoints a peer-mode process listens on (none: peers go through the router)."""
    extra: dict[str, Any] = Field(default_factory=dict)
    """Further Zenoh settings as ``{"path/in/config": value}``."""
    open_timeout_s: float = Field(default=5.0, ge=0.0)
    """How long clients and peers retry reaching the router at start, in [s]."""
    hosts: dict[Identifier, ZenohHost] = Field(default_factory=dict)
    """A show across several machines, by host name: one router per host (``skyquill up SHOW
    --host NAME`` on each); ``router_listen``, ``connect`` and ``router_connect`` above are then
    unused. Empty: one machine."""

    @field_validator("hosts")
    @classmethod
    def _one_ground_station(cls, hosts: dict[str, ZenohHost]) -> dict[str, ZenohHost]:
        if not hosts:
            return hosts
        for name in hosts:
            if not re.match(ID_PATTERN, name):
                raise ValueError(f"host name {name!r} must match {ID_PATTERN}")
        ground = [name for name, host in hosts.items() if host.services]
        if len(ground) != 1:
            raise ValueError(
                f"exactly one host must have services: true (the ground station), not {ground}"
            )
        seen: dict[str, str] = {}
        for name, host in hosts.items():
            if not host.services and not host.router_connect:
                raise ValueError(f"host {name}: router_connect must name the ground router")
            for vehicle_id in host.vehicles:
                if vehicle_id in seen:
                    raise ValueError(
                        f"vehicle {vehicle_id} is on hosts {seen[vehicle_id]} and {name}"
                    )
                seen[vehicle_id] = name
        return hosts


class StorageSettings(ShowModel):
    """Where the orchestrator keeps its durable state. Relative paths, defaults included, start
    from the show file's folder, not the working directory (``showfile/paths.py``)."""

    database: Path | None = None
    """SQLite file of the job queue and event log; default ``out/<show_id>/show.sqlite3``. The
    show's keys (``security.keys_dir``), job files and logs go in its folder."""
    recordings_dir: Path | None = None
    """Directory of the MCAP recordings, one file per run; default ``out/<show_id>/recordings``."""
    record: bool = True
    """Record every message of the show to MCAP."""
    record_scene: bool = True
    """Record beside them the show as a 3D scene in Foxglove's schemas (``scene/``: the vehicles'
    frames, boards, homes, geofences, paths, ink, log and plot series; about half as many bytes
    again as the bus messages)."""
    recording_part_mb: float = Field(default=25.0, gt=0.0)
    """A recording is finished and the next part begun past this size, in [MB]: each part is a
    whole MCAP file, and the recorder's index (which grows with every job) starts afresh."""
    recordings_budget_mb: float = Field(default=2000.0, gt=0.0)
    """Disk for the show's recordings, in [MB]; the oldest parts go first."""
    job_files: Literal["compact", "full"] = "compact"
    """Per-job files next to the database (``jobs/``): ``compact`` keeps a job under ~100 kB
    (metrics, a small picture, the reference and the flight at 20 Hz in one compressed file);
    ``full`` keeps every tick and a full-size picture."""
    job_files_budget_mb: float = Field(default=1000.0, gt=0.0)
    """Disk for job files, in [MB], shared evenly by the vehicles; the oldest go first."""
    job_files_max_age_h: float | None = Field(default=None, gt=0.0)
    """Job files older than this are removed, in [h]; None: only the budget limits them."""
    database_budget_mb: float = Field(default=100.0, gt=0.0)
    """Disk for the SQLite database, in [MB] (its WAL adds up to ~4 MB). Past it, down to 80 %:
    the oldest finished jobs are compacted (strokes and ink picture dropped, ~1.2 kB record
    left), the oldest events deleted, then the oldest records folded into per-state totals and
    a key table (~80 B a job), so counts stay exact and idempotency keys answered; unfinished
    jobs are never touched (``orchestrator/compaction.py``). About 9 MB per hour of show before
    compaction, 0.15 MB once folding."""
    job_history_max_age_h: float | None = Field(default=None, gt=0.0)
    """Finished jobs older than this are compacted and older events deleted, in [h], whatever
    the database's size; None: only the budget limits them."""
    min_free_mb: float = Field(default=64.0, ge=0.0)
    """New characters are refused (``storage_full``) while the database's disk has less than
    this free, in [MB]: room for what the jobs already taken still write (a compact job folder
    is ~100 kB, a recording part ``recording_part_mb``), before SQLite finds the disk full and
    the orchestrator has to stop. 0: never refused."""


class PolicySettings(ShowModel):
    """Moderation and queue policy."""

    moderation: bool = False
    """Submissions wait for an operator's approval before they are queued."""
    lost_after_s: float = Field(default=1.5, gt=0.0)
    """A vehicle whose liveliness token is gone this long is lost; its job is requeued, in [s]."""
    lost_job_hold_s: float = Field(default=15.0, ge=0.0)
    """In [s]: a lost vehicle's job that it cannot have begun (no ready report stored) waits
    this long for it before another may take it; one it may have begun waits for its word
    (``orchestrator/holders.py``: it may have written it in full), and this long past the end
    of its write fence (``bus/fence.py``: it can no longer be inking) the operator is told, and
    may free it with a fresh sheet on its board. 15 s covers a vehicle cut off for 10 s whatever
    the moment of the cut (the fence runs at least ``lost_after_s`` past it), and a restart of
    the router or the orchestrator many times over, without troubling the operator."""
    tracking_error_alert_m: float = Field(default=0.05, gt=0.0)
    """Tracking error that raises an alert event while a vehicle writes, in [m]."""
    max_queue: int = Field(default=200, ge=1)
    """Submissions beyond this many queued jobs are refused (``queue_full``); jobs awaiting
    approval count apart (``max_awaiting``). The operator's own are never refused."""
    max_awaiting: int = Field(default=100, ge=1)
    """With moderation, submissions beyond this many jobs awaiting approval are refused
    (``queue_full``): unmoderated jobs never fill the queue of approved ones. The operator's own
    are never refused."""
    client_submits_per_minute: int = Field(default=6, ge=1)
    """Submissions per sliding minute from each outside client's certificate (``skyquill keys
    --client``), refused past it (``rate_limited``): the kiosk's rule and default for one address
    (``kiosk.rate_limit_per_minute``), since an outside client is one submitter. The operator's
    own are never limited (``orchestrator/quotas.py``)."""
    kiosk_submits_per_minute: int = Field(default=60, ge=1)
    """Submissions per sliding minute from the kiosk, all its visitors together (the kiosk limits
    each address itself): one a second, ten visitors at the kiosk's per-address default at once,
    more than a busy kiosk's few tablets hand in (a visitor takes tens of seconds to draw) and
    than a fleet writes, yet a bound if the kiosk is abused from many addresses."""
    client_max_waiting: int = Field(default=10, ge=1)
    """Jobs of one outside client that may wait (awaiting approval or queued) at once; past it
    its submissions are refused (``rate_limited``) until one is approved, rejected or written."""
    max_attempts: int = Field(default=3, ge=1)
    """A job fails instead of being requeued again after this many attempts that may have been
    its own fault: its vehicle lost or restarted with it, or a safety abort (``not_settled``)."""
    max_handbacks: int = Field(default=10, ge=1)
    """A job fails after being handed back this many times for reasons that are not its own
    (uncounted by ``max_attempts``): an assignment refused or unanswered, a take-off refused,
    a kind that cannot write it, or a present vehicle that gave it up unconfirmed (its lease
    ran out under load or on a poor link). Bounds them so that nothing goes round for ever."""
    fleet_period_s: float = Field(default=1.0, gt=0.0)
    """Period of the fleet snapshot publication, in [s]."""
    sheet_change_s: float = Field(default=40.0, gt=0.0)
    """Show seconds the crew is expected to take to change a sheet, for the ETAs until it has
    changed some (then the median of its last ten: ``orchestrator/sheets.py``). Not from the
    papers, which give no figure: a first guess (walk to the board, unclip, clip), replaced by
    the day's own pace."""


KIOSK_BODY_MAX_BYTES = 256_000
"""Largest kiosk body a show may allow: the kiosk passes a drawing on in one bus request, which
carries at most 256 KiB (``bus/codec.py``, docs/protocol.md), less room for its other fields."""
DRAWN_POINT_BYTES = 48
"""JSON bytes of one point as the drawing pad sends it with a width at most
(``{"x":1920.5,"y":1080.5,"t":600.123,"w":0.01234},``, ``kiosk/static/widths.js``)."""
BODY_ENVELOPE_BYTES = 2_000
"""A drawing's body beyond its points: brackets, canvas, units, language."""


class KioskSettings(ShowModel):
    """The public web kiosk."""

    host: str = "127.0.0.1"
    """Address the kiosk's HTTP server binds to."""
    port: int = Field(default=8765, ge=1, le=65535)
    """TCP port of the kiosk."""
    rate_limit_per_minute: int = Field(default=6, ge=1)
    """Submissions accepted per client address per minute (whatever its cookies)."""
    trusted_proxies: tuple[IPvAnyNetwork, ...] = ()
    """Reverse proxies (addresses or networks, e.g. ``["127.0.0.1"]``) whose ``X-Forwarded-For``
    names the client; none by default: the header is then ignored."""
    max_payload_bytes: int = Field(default=250_000, ge=1, le=KIOSK_BODY_MAX_BYTES)
    """Largest request body, in bytes: room for ``max_points`` drawn with widths
    (:data:`DRAWN_POINT_BYTES` each), within what one bus request carries."""
    max_strokes: int = Field(default=60, ge=1)
    """Most strokes in one drawing."""
    max_points: int = Field(default=5000, ge=2)
    """Most points in one drawing, all strokes together."""
    max_text_chars: int = Field(default=1, ge=1, le=64)
    """Longest typed text, in characters (1: one letter or one Chinese character)."""
    blocklist: tuple[str, ...] = ()
    """Texts refused by the kiosk (compared after Unicode normalisation, case-folded)."""
    max_flight_s: float = Field(default=90.0, gt=0.0)
    """Longest planned writing flight of one character, in [s]; longer ones are refused with
    the reason before they are sent."""
    idle_reset_s: float = Field(default=60.0, ge=0.0)
    """A page left alone this long goes back to the start (shared tablets), in [s]; 0: never."""

    @model_validator(mode="after")
    def _room_for_the_points(self) -> KioskSettings:
        """A drawing of ``max_points`` must fit in a body, or the biggest drawings a visitor
        may make would be refused as too large."""
        needed = self.max_points * DRAWN_POINT_BYTES + BODY_ENVELOPE_BYTES
        if needed > self.max_payload_bytes:
            raise ValueError(
                f"max_payload_bytes {self.max_payload_bytes} cannot carry max_points "
                f"{self.max_points} drawn with widths ({needed} bytes): raise it or lower "
                f"max_points"
            )
        return self


class BatterySettings(ShowModel):
    """How the orchestrator plans around batteries (``orchestrator/batteries.py``)."""

    reserve_fraction: float = Field(default=0.20, ge=0.0, lt=1.0)
    """Charge a vehicle must still hold after writing a job, returning and landing, over its
    pack's rated capacity; below it the vehicle is sent for a swap. 0.20: the LiPo users' "80 %
    rule" (a pack is not drawn below a fifth of its charge, for its cells' life), which also
    keeps every landing above PX4's low-battery warning (``BAT_LOW_THR`` 0.15 by default)."""
    swap_s: float = Field(default=60.0, gt=0.0)
    """Show seconds the crew is expected to take to swap a battery, from the vehicle's wait to
    their confirmation, for the ETAs until it has swapped some (then the median of its last ten,
    as for sheets). Not from the papers: a first guess (walk to the vehicle, unplug, swap, plug in,
    step back), replaced by the day's own pace."""


class PreflightSettings(ShowModel):
    """The agent's preflight before a vehicle takes jobs (``vehicle_agent/preflight.py``); the
    battery's bound is ``battery.reserve_fraction``."""

    link_age_max_s: float = Field(default=2.0, gt=0.0)
    """Oldest autopilot heartbeat in [s] a vehicle may take off on. MAVLink's heartbeat is 1 Hz
    and a ground station takes a link as lost after four or five missed
    (mavlink.io/en/services/heartbeat.html); 2 s is one missed, enough to wait before a take-off
    and below the agent's own lost-link fault (``heartbeat_timeout_s``, 3 s)."""
    link_loss_max_fraction: float = Field(default=0.05, ge=0.0, le=1.0)
    """Most autopilot messages lost (counted from their MAVLink sequence numbers) over the
    recent window. A healthy IP link loses under 1e-3 (ITU-T Y.1541's objective for its
    classes 0-4) and a wired serial link none: 5 % is a link that is failing, not a noisy one."""
    mocap_age_max_s: float = Field(default=0.2, gt=0.0)
    """Oldest mocap pose in [s] forwarded to the autopilot (a vehicle with ``mavlink_mocap``):
    half of PX4 EKF2's vision timeout (2 x ``EV_MAX_INTERVAL``, 0.4 s) and under ArduPilot's
    0.3 s, so the vehicle is held before its estimator drops its position source."""
    clock_offset_max_s: float = Field(default=0.05, gt=0.0)
    """Largest offset in [s] of the agent's clock from the orchestrator's, measured by a
    request and its reply. NTP keeps hosts on a LAN within a millisecond (RFC 5905, ntp.org)
    and PTP within microseconds: 50 ms is a clock that is not synchronised at all, and one
    telemetry period (20 Hz), so recordings and the event log still line up within a sample."""

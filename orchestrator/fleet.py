"""The orchestrator's view of the vehicles, and queue ETAs (pure)."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass

from bus.messages import VehicleStateName, VehicleSummary
from orchestrator import phrase_rows
from orchestrator.batteries import EtaCharges
from orchestrator.jobs import Job

READY_STATES: frozenset[str] = frozenset({"idle", "landed"})
"""Vehicle states in which a vehicle may take a new job."""
RELAY_BURST = 10.0
"""Log lines a vehicle's own words (its events, its ``ended`` reports) make at once, before the
rate limit applies."""
RELAY_RATE_PER_S = 1.0
"""Log lines of a vehicle's own words per second, sustained."""


@dataclass(frozen=True)
class VehicleInfo:
    """A vehicle as the show file declares it."""

    vehicle_id: str
    """Vehicle id."""
    kind: str
    """Vehicle kind, e.g. ``quadrotor-brush``."""
    board_id: str
    """The board it writes on."""
    cannot_write: str | None = None
    """Why it can write no job (its kind does not write on its board's surface, or it cannot
    reach it), in one line; None: it can. Such a vehicle is never given a job."""


@dataclass
class VehicleView:
    """What the orchestrator currently knows about one vehicle (mutable, owned by the Book)."""

    info: VehicleInfo
    """Declaration from the show file."""
    alive: bool = False
    """Its liveliness token is present (not enough to be taken as present: see ``heard_at_s``)."""
    state: VehicleStateName = "lost"
    """Last state the vehicle reported."""
    lost: bool = True
    """Token gone, or silent, for ``lost_after_s`` (or never heard): shown as ``lost``."""
    reported_job_id: str | None = None
    """Job the vehicle last said it works on."""
    status_at_s: float | None = None
    """Orchestrator time of its last status, [s]."""
    last_seen_s: float | None = None
    """Orchestrator time of its last status, telemetry or liveliness change, [s]."""
    gone_since_s: float | None = None
    """Orchestrator time its token disappeared (or the orchestrator started), [s]."""
    heard_at_s: float | None = None
    """Orchestrator time of the last message it sent itself (status or telemetry, on its own
    keys), [s]: the heartbeat; a token alone (which anyone may fake) keeps no vehicle present."""
    token_at_s: float | None = None
    """Orchestrator time its token last appeared, [s] (its first status is due from then)."""
    incarnation: str | None = None
    """The ``incarnation`` of its latest status (a new one: its agent restarted)."""
    restarted_at_s: float | None = None
    """Orchestrator time of its first status with a new ``incarnation`` (its agent restarted),
    [s]."""
    checked_at_s: float | None = None
    """Orchestrator time its presence was last checked, [s]; a long gap means the orchestrator
    itself stalled, and heartbeats that queued up meanwhile are waited for once."""
    resumed_at_s: float | None = None
    """Orchestrator time it last resumed after such a stall, [s]."""
    was_seen: bool = False
    """It has been alive at least once since the orchestrator started."""
    paused: bool = False
    """The operator stopped giving it jobs (pause, land, estop)."""
    held: bool = False
    """Landed or stopped by the operator, found in ``fault``, or back from a loss in the air: no
    job until an explicit ``release`` (not ``resume``); stored, so no restart sheds it."""
    lost_in_state: VehicleStateName | None = None
    """The airborne state it was lost in (None: not lost in the air): back without its job, it is
    held (``orchestrator/presence.py``)."""
    refused_until_s: float = 0.0
    """No new assignment before this time, [s] (after a refused or unanswered assignment)."""
    mismatch_since_s: float | None = None
    """Since when its status has not mentioned the job the orchestrator gave it, [s]."""
    message: str = "not connected"
    """Human note for displays."""
    preflight: str = ""
    """Why the vehicle cannot take off now, in its autopilot's words (its status's
    ``preflight``); empty: it can. It gets no job meanwhile: arming would only be refused."""
    battery_fraction: float | None = None
    """Charge left in its battery, 0..1, as its latest status said (None: not reported)."""
    battery_minutes_left: float | None = None
    """Minutes until its battery is empty, as its latest status said."""
    link_loss_fraction: float | None = None
    """Share of its autopilot's messages lost, as its latest status said."""
    flight_s_today: float | None = None
    """Its time off the ground today in [s], as its latest status said."""
    clock_off: bool = False
    """Its clock was reported past ``clock_offset_max_s`` (the ``clock_offset`` alert is open
    until it is reported within it again; ``orchestrator/clock_offsets.py``)."""
    swap_reason: str = ""
    """Why it was sent for a battery swap (``orchestrator/batteries.py``), in one line; empty:
    it was not, or its fresh pack has reported. It gets no job meanwhile."""
    last_alert_s: float = -1e18
    """Orchestrator time of its last tracking alert, [s]."""
    event_tokens: float = 10.0
    """Events of this vehicle that may still be relayed into the log at once (token bucket)."""
    event_tokens_at_s: float | None = None
    """Orchestrator time ``event_tokens`` was last refilled, [s]."""

    def may_log(self, now_s: float) -> bool:
        """Whether a line of this vehicle's own words may go into the show's log now (a token
        bucket: :data:`RELAY_BURST` at once, then :data:`RELAY_RATE_PER_S`); takes its token."""
        since = self.event_tokens_at_s if self.event_tokens_at_s is not None else now_s
        self.event_tokens = min(RELAY_BURST, self.event_tokens + (now_s - since) * RELAY_RATE_PER_S)
        self.event_tokens_at_s = now_s
        if self.event_tokens < 1.0:
            return False
        self.event_tokens -= 1.0
        return True

    def summary(self, job_id: str | None) -> VehicleSummary:
        """The wire view of this vehicle."""
        swapping = self.swap_reason and not self.lost and self.state in READY_STATES
        return VehicleSummary(
            vehicle_id=self.info.vehicle_id,
            kind=self.info.kind,
            state="lost" if self.lost else "battery_swap" if swapping else self.state,
            alive=self.alive,
            board_id=self.info.board_id,
            job_id=job_id,
            last_seen_s=self.last_seen_s,
            message=self._note() + (" (paused)" if self.paused and not self.held else ""),
            held=self.held,
            paused=self.paused and not self.held,
            battery_fraction=self.battery_fraction,
            battery_minutes_left=self.battery_minutes_left,
            preflight="" if self.lost else self.preflight,
            link_loss_fraction=self.link_loss_fraction,
            flight_s_today=self.flight_s_today,
        )

    def _note(self) -> str:
        """Its message, after what its autopilot waits for (a vehicle present), or why it waits
        for a battery swap."""
        if self.swap_reason and not self.lost:
            return f"battery swap: {self.swap_reason}"
        if not self.preflight or self.lost:
            return self.message
        waiting = f"held by its preflight: {self.preflight}"
        return f"{waiting}; {self.message}" if self.message else waiting


def ready_for_job(view: VehicleView, now_s: float) -> bool:
    """Healthy and idle by its own account, not paused, not backing off, its preflight passed
    (a ground station does not offer arming before the pre-arm checks pass either)."""
    return waiting_on_ground(view, now_s) and not view.preflight


def waiting_on_ground(view: VehicleView, now_s: float) -> bool:
    """:func:`ready_for_job` but for its preflight: a vehicle held by it (a flat battery among
    others) may still be sent for a battery swap."""
    return (
        view.alive
        and not view.lost
        and not view.paused
        and not view.held
        and view.status_at_s is not None
        and view.state in READY_STATES
        and view.reported_job_id is None
        and not view.swap_reason
        and view.refused_until_s <= now_s
        and view.info.cannot_write is None
    )


def usable_boards_of(vehicles: Mapping[str, VehicleView]) -> dict[str, str]:
    """Vehicle id -> board of every vehicle that may take jobs, for :func:`queue_etas`: alive,
    present, neither paused nor held."""
    return {
        vid: v.info.board_id
        for vid, v in vehicles.items()
        if v.alive and not v.lost and not (v.paused or v.held)
    }


def landing_of(
    vehicles: Mapping[str, VehicleView], usable: Iterable[str], active: Iterable[Job]
) -> list[str]:
    """The ``usable`` vehicles without an ``active`` job still on their way down, for
    :func:`queue_etas`."""
    busy = {j.vehicle_id for j in active}
    return [
        vid for vid in usable if vid not in busy and vehicles[vid].state in ("returning", "landing")
    ]


@dataclass(frozen=True)
class EtaModel:
    """Timing assumptions of the ETA estimate, in sim seconds unless said otherwise.

    A job's life on a vehicle: assigned -> ``before_write_s`` (the agent plans on the ground,
    climbs, flies to the start of the plan and settles) -> writing for its planned duration ->
    ``done`` (the board is free) -> ``after_write_s`` (return above home, land, report ready
    again) -> the vehicle takes its next job. The defaults are the medians measured on the
    Airshow show by ``benchmarks/bench_show.py --eta-only`` (11.2 s and 8.8 s, 2-core machine
    under load).
    """

    time_scale: float = 1.0
    """Simulated seconds per wall-clock second (the show's ``time_scale``)."""
    before_write_s: float = 11.0
    """From assignment to the start of writing, [s]."""
    after_write_s: float = 9.0
    """From the end of writing until the vehicle can take its next job, [s]."""


def writing_s(job: Job) -> float:
    """Sim seconds of writing of a job: the planned duration once known, else its estimate."""
    return job.planned_duration_s or job.estimate_s


def remaining_s(job: Job, now_s: float, model: EtaModel) -> float:
    """Sim seconds until an active job is written (``done``): what is left of the approach
    (``assigned``) and of the writing."""
    if job.state == "writing":
        return max(0.0, writing_s(job) * (1.0 - job.progress))
    since_s = (now_s - (job.assigned_at_s if job.assigned_at_s is not None else now_s)) * (
        model.time_scale
    )
    return max(0.0, model.before_write_s - since_s) + writing_s(job)


def queue_etas(
    queue: Sequence[Job],
    active: Iterable[Job],
    usable_boards: Mapping[str, str],
    now_s: float,
    model: EtaModel,
    *,
    landing: Iterable[str] = (),
    may_take: Callable[[Job, str], bool] | None = None,
    writing_s_on: Callable[[Job, str], float] | None = None,
    board_free_s: Mapping[str, float] | None = None,
    after_character_s: Callable[[str], float] | None = None,
    charges: EtaCharges | None = None,
    row: Sequence[str] = (),
) -> dict[str, float]:
    """Wall seconds from now until each queued job should start writing (list scheduling).

    ``usable_boards`` maps every vehicle that may take jobs to its board; ``active`` are the
    jobs on vehicles (they keep their vehicle until written, then its board is free and the
    vehicle lands); ``landing`` are usable vehicles without a job still on their way down
    (half of ``after_write_s`` left, on average). The head of the queue goes to the vehicle that
    can start it first: when it is free and its board is too (one job per board at a time).
    Empty when no vehicle is usable. ``may_take(job, vehicle_id)`` (default: always) leaves out
    the vehicles whose kind cannot write a job; a job no usable vehicle may take has no ETA.
    ``writing_s_on(job, vehicle_id)`` (default: the job's own estimate) is how long the job writes
    on that vehicle (kinds differ). ``board_free_s``: when each board may take a job (Unix
    time [s]: a sheet being changed, a surface drying; default now); ``after_character_s(board)``
    (default 0): show seconds a board takes no job after each character (the crew's sheet).
    ``charges`` (default: batteries not counted): the vehicles' charge, spent job by job; a job
    its vehicle cannot take with the reserve starts after a swap (``orchestrator/batteries.py``).
    ``row``: the boards left to right; the characters of a phrase start together when a window
    of adjacent boards has a vehicle free for each, and the vehicles of the boards it could
    use start nothing behind it before (``orchestrator/phrases.py``).
    """
    schedule = _Schedule(
        boards=usable_boards,
        model=model,
        vehicle_free_s=_vehicles_free_s(usable_boards, landing, charges, now_s, model),
        board_free_s={
            b: max(now_s, (board_free_s or {}).get(b, now_s)) for b in usable_boards.values()
        },
        may_take=may_take,
        writing_s_on=writing_s_on,
        after_character_s=after_character_s,
        charges=charges,
    )
    for job in active:
        _hold_active(schedule, job, now_s)
    etas: dict[str, float] = {}
    if not schedule.vehicle_free_s:
        return etas
    for unit in phrase_rows.units(queue):
        _place(schedule, unit, row, now_s, etas)
    return etas


@dataclass
class _Schedule:
    """The list schedule of :func:`queue_etas` as it fills: when each usable vehicle and each
    board is next free, Unix time [s], and what decides how long each job takes them."""

    boards: Mapping[str, str]
    """Vehicle id -> board, of every vehicle that may take jobs."""
    model: EtaModel
    vehicle_free_s: dict[str, float]
    """Vehicle id -> when it may take its next job, Unix time [s]."""
    board_free_s: dict[str, float]
    """Board id -> when it may take its next job, Unix time [s]."""
    may_take: Callable[[Job, str], bool] | None
    writing_s_on: Callable[[Job, str], float] | None
    after_character_s: Callable[[str], float] | None
    charges: EtaCharges | None


def _vehicles_free_s(
    usable_boards: Mapping[str, str],
    landing: Iterable[str],
    charges: EtaCharges | None,
    now_s: float,
    model: EtaModel,
) -> dict[str, float]:
    """When each usable vehicle is free but for the active jobs, Unix time [s]: now, half of
    ``after_write_s`` on if it is landing, once its battery swap is done if it waits for one."""
    vehicle_free = dict.fromkeys(usable_boards, now_s)
    for vid in set(landing) & vehicle_free.keys():
        vehicle_free[vid] = now_s + model.after_write_s / 2 / model.time_scale
    for vid, free_s in (charges.free_at_s if charges else {}).items():
        if vid in vehicle_free:
            vehicle_free[vid] = max(vehicle_free[vid], free_s)
    return vehicle_free


def _after_s(schedule: _Schedule, board_id: str) -> float:
    """Wall seconds the board takes no job after each character (the crew's sheet)."""
    after_character_s = schedule.after_character_s
    return after_character_s(board_id) / schedule.model.time_scale if after_character_s else 0.0


def _hold_active(schedule: _Schedule, job: Job, now_s: float) -> None:
    """An active job keeps its vehicle until written, then its board is free and the vehicle
    lands; its charge is spent."""
    scale, charges = schedule.model.time_scale, schedule.charges
    done = now_s + remaining_s(job, now_s, schedule.model) / scale
    board_free = schedule.board_free_s
    if job.board_id is not None:
        free = done + _after_s(schedule, job.board_id)
        board_free[job.board_id] = max(board_free.get(job.board_id, now_s), free)
    if job.vehicle_id in schedule.vehicle_free_s:
        schedule.vehicle_free_s[job.vehicle_id] = done + schedule.model.after_write_s / scale
        if charges is not None:  # the whole job, though part of it is flown: on the safe side
            charges.spend(job, job.vehicle_id)


def _can_start(schedule: _Schedule, job: Job, vid: str) -> tuple[float, str]:
    """When ``vid`` could start ``job`` (it and its board free, after a swap if the job needs
    one), and ``vid``."""
    scale, charges = schedule.model.time_scale, schedule.charges
    swap_s = charges.swap_s / scale if charges and charges.swap_first(job, vid) else 0.0
    board_free_s = schedule.board_free_s[schedule.boards[vid]]
    return max(schedule.vehicle_free_s[vid] + swap_s, board_free_s), vid


def _option(schedule: _Schedule, job: Job, board_id: str | None = None) -> tuple[float, str] | None:
    """The earliest start of ``job`` and its vehicle, among those that may take it (on
    ``board_id`` only, unless None); None: no usable vehicle may take it."""
    takers = [
        v
        for v in schedule.vehicle_free_s
        if (schedule.may_take is None or schedule.may_take(job, v))
        and board_id in (None, schedule.boards[v])
    ]
    return min((_can_start(schedule, job, v) for v in takers), default=None)


def _place(
    schedule: _Schedule,
    unit: Sequence[Job],
    row: Sequence[str],
    now_s: float,
    etas: dict[str, float],
) -> None:
    """Seat a unit of the queue (a job, or a phrase's characters) where it starts first, and
    put its jobs' ETAs in ``etas``."""
    together = phrase_rows.together(unit[0])
    if together:  # all start when a window of them is free
        best = phrase_rows.best_window(unit, row, lambda job, b: _option(schedule, job, b))
    else:
        first = _option(schedule, unit[0])
        best = None if first is None else (first[0], [(unit[0], first[1])])
    if best is None:
        return
    assigned, seats = best
    for job, vid in seats:
        etas[job.job_id] = _seat(schedule, job, vid, assigned) - now_s
    if together:  # nothing behind it goes first where it could go
        held = phrase_rows.could_use(unit, row, schedule.boards, schedule.may_take)
        for v, board_id in schedule.boards.items():
            if board_id in held:
                schedule.vehicle_free_s[v] = max(schedule.vehicle_free_s[v], assigned)


def _seat(schedule: _Schedule, job: Job, vid: str, assigned_s: float) -> float:
    """``vid`` takes ``job`` at ``assigned_s`` (its charge spent, it and its board busy until
    the job is written); returns when the job starts writing, Unix time [s]."""
    scale = schedule.model.time_scale
    if schedule.charges is not None:
        schedule.charges.spend(job, vid)
    start = assigned_s + schedule.model.before_write_s / scale
    writing = schedule.writing_s_on(job, vid) if schedule.writing_s_on else writing_s(job)
    done = start + writing / scale
    board_id = schedule.boards[vid]
    schedule.board_free_s[board_id] = done + _after_s(schedule, board_id)
    schedule.vehicle_free_s[vid] = done + schedule.model.after_write_s / scale
    return start

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
    scale = model.time_scale
    vehicle_free = dict.fromkeys(usable_boards, now_s)
    for vid in set(landing) & vehicle_free.keys():
        vehicle_free[vid] = now_s + model.after_write_s / 2 / scale
    for vid, free_s in (charges.free_at_s if charges else {}).items():
        if vid in vehicle_free:
            vehicle_free[vid] = max(vehicle_free[vid], free_s)
    board_free = {b: max(now_s, (board_free_s or {}).get(b, now_s)) for b in usable_boards.values()}

    def after_s(board_id: str) -> float:
        return after_character_s(board_id) / scale if after_character_s else 0.0

    for job in active:
        done = now_s + remaining_s(job, now_s, model) / scale
        if job.board_id is not None:
            free = done + after_s(job.board_id)
            board_free[job.board_id] = max(board_free.get(job.board_id, now_s), free)
        if job.vehicle_id in vehicle_free:
            vehicle_free[job.vehicle_id] = done + model.after_write_s / scale
            if charges is not None:  # the whole job, though part of it is flown: on the safe side
                charges.spend(job, job.vehicle_id)
    etas: dict[str, float] = {}
    if not vehicle_free:
        return etas

    def can_start(job: Job, vid: str) -> tuple[float, str]:
        swap_s = charges.swap_s / scale if charges and charges.swap_first(job, vid) else 0.0
        return max(vehicle_free[vid] + swap_s, board_free[usable_boards[vid]]), vid

    def option(job: Job, board_id: str | None = None) -> tuple[float, str] | None:
        takers = [
            v
            for v in vehicle_free
            if (may_take is None or may_take(job, v)) and board_id in (None, usable_boards[v])
        ]
        return min((can_start(job, v) for v in takers), default=None)

    for unit in phrase_rows.units(queue):
        if phrase_rows.together(unit[0]):  # all start when a window of them is free
            best = phrase_rows.best_window(unit, row, option)
        else:
            first = option(unit[0])
            best = None if first is None else (first[0], [(unit[0], first[1])])
        if best is None:
            continue
        assigned, seats = best
        for job, vid in seats:
            if charges is not None:
                charges.spend(job, vid)
            start = assigned + model.before_write_s / scale
            done = start + (writing_s_on(job, vid) if writing_s_on else writing_s(job)) / scale
            etas[job.job_id] = start - now_s
            board_free[usable_boards[vid]] = done + after_s(usable_boards[vid])
            vehicle_free[vid] = done + model.after_write_s / scale
        if phrase_rows.together(unit[0]):  # nothing behind it goes first where it could go
            held = phrase_rows.could_use(unit, row, usable_boards, may_take)
            for v, board_id in usable_boards.items():
                if board_id in held:
                    vehicle_free[v] = max(vehicle_free[v], assigned)
    return etas

"""A show day on the orchestrator's own :class:`~orchestrator.core.Book`, on a simulated clock.

The Book (``orchestrator.outputs.core_config`` of the show: its dispatch, its battery reserve, its
sheets) is fed what a show's services would feed it, at the show seconds they would: visitors'
submissions, the agents' replies, reports and statuses, the crew's confirmations. The vehicles
are not flown: each job takes the phases ``bench_show.cycle`` computed for its character
(planning measured, climb, transit, writing, return, landing), and its pack (the kind's room,
``vehicles.batteries``) is drawn through them on :func:`sim.battery.discharge` at the room's
power of each phase (hover while airborne, rest while planning on the ground).

Visitors arrive as a Poisson process; each hands in a character of the corpus, drawn uniformly.
The crew answers each swap and each sheet after its own draw from a log-normal turnaround (not
one person in a queue: the Airshow had a crew around the four boards).

Where each vehicle's day goes, show seconds: writing, planning, transit (climb, transit, return
and landing), and on the ground: for submissions (an empty queue: whatever else it waits for
then costs nothing), or, with a character queued, for a battery swap (from being sent to the
fresh pack), for a sheet, or other (a queue it could not take from).
"""

from __future__ import annotations

import heapq
import math
import random
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import partial

from bus.messages import (
    AgentReport,
    CommandReply,
    JobMetrics,
    OperatorCommand,
    SubmitRequest,
    VehicleStatus,
)
from orchestrator.core import Book, CoreConfig, Effects
from sim.battery import BatteryState, VehicleBattery, discharge, full

CAUSES = ("battery swaps", "sheets", "planning", "transit", "no submissions", "other")
"""Where a vehicle's time goes that is not writing."""
TIME_USES = ("writing", *CAUSES)
KEPT_QUEUED = 2
"""Characters queued per vehicle in a day with more visitors than the fleet can serve."""
DRAW_STEP_S = 5.0
"""Step of the pack's discharge through a phase, [s]."""


@dataclass(frozen=True)
class Phases:
    """One character's job on a vehicle, show seconds."""

    plan_s: float
    to_write_s: float
    """Climb and transit to the start of the character."""
    write_s: float
    back_s: float
    """Return and landing."""


@dataclass(frozen=True)
class Crew:
    """The crew's turnaround: log-normal, by its median [s] and the sigma of its logarithm."""

    sheet_median_s: float = 30.0
    swap_median_s: float = 90.0
    sigma: float = 0.5

    def turnaround_s(self, rng: random.Random, median_s: float) -> float:
        return rng.lognormvariate(math.log(median_s), self.sigma)


@dataclass
class DayResult:
    """What a day came to."""

    hours: float
    written_at_s: list[float] = field(default_factory=list)
    swaps: int = 0
    sheets: int = 0
    submitted: int = 0
    refused: int = 0
    lost_s: dict[str, float] = field(default_factory=lambda: dict.fromkeys(TIME_USES, 0.0))
    """Cause -> vehicle-seconds of the day, summed over the fleet (``writing`` too)."""

    def per_hour(self) -> list[int]:
        """Characters written in each hour of the day."""
        counts = Counter(int(t // 3600.0) for t in self.written_at_s)
        return [counts[h] for h in range(math.ceil(self.hours))]


@dataclass
class _Vehicle:
    vehicle_id: str
    board: str
    pack: BatteryState
    busy_as: str | None = None
    """The cause its time counts to while it flies a job (None: on the ground, free)."""


class ShowDay:
    """One day's events, in show-time order."""

    def __init__(
        self,
        config: CoreConfig,
        phases: Callable[[str], Phases],
        battery: VehicleBattery | None,
        crew: Crew,
        seed: int,
    ) -> None:
        # statuses come at the day's events, not every 0.37 s: no vehicle is found silent
        self.book = Book(replace(config, lost_after_s=math.inf), now_s=0.0)
        self.phases, self.battery, self.crew = phases, battery, crew
        self.rng = random.Random(seed)
        self.now_s = 0.0
        self._events: list[tuple[float, int, Callable[[], None]]] = []
        self._seq = 0
        self.vehicles = {
            v.vehicle_id: _Vehicle(v.vehicle_id, v.board_id, full_pack(battery))
            for v in config.vehicles
        }
        self.result = DayResult(hours=0.0)
        self._crew_on: set[str] = set()
        """Vehicles and boards the crew is on its way to."""
        self._chars: dict[str, str] = {}
        """Job id -> its character."""
        """Vehicles and boards the crew is on its way to."""

    def at(self, t_s: float, action: Callable[[], None]) -> None:
        self._seq += 1
        heapq.heappush(self._events, (t_s, self._seq, action))

    def run(self, hours: float, arrivals_per_h: float | None, corpus: str) -> DayResult:
        """The day; ``arrivals_per_h`` None: a visitor whenever fewer than :data:`KEPT_QUEUED`
        characters per vehicle are queued (more visitors than the fleet can serve)."""
        self.result.hours = hours
        end_s = hours * 3600.0
        for vid in self.vehicles:
            self.apply(self.book.liveliness(vid, True, 0.0))
            self._status(vid, "idle")
        t = 0.0 if arrivals_per_h is None else self.rng.expovariate(arrivals_per_h / 3600.0)
        while arrivals_per_h is not None and t < end_s:
            self.at(t, partial(self._visitor, self.rng.choice(corpus)))
            t += self.rng.expovariate(arrivals_per_h / 3600.0)
        kept = KEPT_QUEUED * len(self.vehicles) if arrivals_per_h is None else 0
        while len(self.book.queue()) < kept:
            self._visitor(self.rng.choice(corpus))
        while self._events and self._events[0][0] < end_s:
            t_s, _, action = heapq.heappop(self._events)
            self._account(t_s)
            action()
            self.apply(self.book.tick(self.now_s))
            while len(self.book.queue()) < kept:
                self._visitor(self.rng.choice(corpus))
        self._account(end_s)
        return self.result

    # --- time accounting ---------------------------------------------------------------------
    def _account(self, t_s: float) -> None:
        dt_s = t_s - self.now_s
        if dt_s > 0.0:
            for v in self.vehicles.values():
                self.result.lost_s[v.busy_as or self._ground_cause(v)] += dt_s
        self.now_s = t_s

    def _ground_cause(self, v: _Vehicle) -> str:
        book, vid = self.book, v.vehicle_id
        if not book.queue():
            return "no submissions"  # nothing to write: a swap or a sheet then costs nothing
        if book.vehicles[vid].swap_reason or vid in book.swaps.waiting:
            return "battery swaps"
        return "sheets" if v.board in book.sheet_wanted() else "other"

    # --- the Book's effects, carried out --------------------------------------------------------
    def apply(self, eff: Effects) -> None:
        for vid, command in eff.commands:
            if command.command == "assign" and command.job is not None:
                self._fly(vid, command.job.job_id, self._chars[command.job.job_id])
            elif command.command == "battery_swapped":
                self.vehicles[vid].pack = full_pack(self.battery)
                self.at(self.now_s, partial(self._status, vid, "idle"))
        for vid in self.book.swaps.waiting.keys() - self._crew_on:
            self.result.swaps += 1
            self._crew_later(
                vid,
                self.crew.swap_median_s,
                OperatorCommand(command="battery_swapped", vehicle_id=vid),
            )
        for board in self.book.sheets.waiting.keys() - self._crew_on:
            self.result.sheets += 1
            self._crew_later(
                board,
                self.crew.sheet_median_s,
                OperatorCommand(command="fresh_sheet", board_id=board),
            )

    def _crew_later(self, target: str, median_s: float, command: OperatorCommand) -> None:
        """The crew answers for ``target`` (a vehicle or a board) after its turnaround."""
        self._crew_on.add(target)

        def confirm() -> None:
            self._crew_on.discard(target)
            self.apply(self.book.operator(command, self.now_s)[1])

        self.at(self.now_s + self.crew.turnaround_s(self.rng, median_s), confirm)

    def _visitor(self, char: str) -> None:
        self.result.submitted += 1
        job_id = f"j{self.result.submitted}"
        self._chars[job_id] = char
        estimate_s = self.phases(char).write_s
        reply, eff = self.book.submit(
            job_id, SubmitRequest(text=char), label=char, estimate_s=estimate_s, now_s=self.now_s
        )
        if not reply.ok:
            self.result.refused += 1
        self.apply(eff)

    def _status(self, vid: str, state: str, job_id: str | None = None) -> None:
        v = self.vehicles[vid]
        charge = None if self.battery is None else v.pack.charge_fraction
        status = VehicleStatus(
            vehicle_id=vid,
            kind="quadrotor-brush",
            state=state,  # type: ignore[arg-type]
            job_id=job_id,
            battery_fraction=charge,
        )
        self.apply(self.book.status(status, self.now_s))

    # --- one job ------------------------------------------------------------------------------
    def _fly(self, vid: str, job_id: str, char: str) -> None:
        v, p = self.vehicles[vid], self.phases(char)
        self.apply(self.book.assignment_result(vid, job_id, CommandReply(ok=True), self.now_s))
        v.busy_as = "planning"
        self.at(self.now_s, lambda: self._status(vid, "idle", job_id))  # planning it
        t_fly = self.now_s + p.plan_s
        t_write = t_fly + p.to_write_s
        t_back = t_write + p.write_s
        t_idle = t_back + p.back_s

        def take_off() -> None:
            v.busy_as = "transit"
            self._draw(v, "rest", p.plan_s)
            self._status(vid, "taking_off", job_id)

        def write() -> None:
            v.busy_as = "writing"
            self._draw(v, "transit", p.to_write_s)
            self._report(vid, job_id, "started", planned_duration_s=p.write_s)
            self._status(vid, "writing", job_id)

        def done() -> None:
            v.busy_as = "transit"
            self._draw(v, "writing", p.write_s)
            metrics = JobMetrics(
                rmse_pen_down_m=0.01, rmse_m=0.01, max_error_m=0.02, iou=0.9, duration_s=p.write_s
            )
            self._report(vid, job_id, "done", metrics=metrics)
            self.result.written_at_s.append(self.now_s)
            self._status(vid, "returning")

        def landed() -> None:
            v.busy_as = None
            self._draw(v, "transit", p.back_s)
            self._status(vid, "idle")

        for t_s, action in ((t_fly, take_off), (t_write, write), (t_back, done), (t_idle, landed)):
            self.at(t_s, action)

    def _report(self, vid: str, job_id: str, event: str, **fields: object) -> None:
        report = AgentReport(vehicle_id=vid, job_id=job_id, event=event, **fields)  # type: ignore[arg-type]
        self.apply(self.book.report(report, self.now_s)[1])

    def _draw(self, v: _Vehicle, phase: str, duration_s: float) -> None:
        """``v``'s pack through ``duration_s`` [s] of ``phase`` (rest, transit, writing)."""
        if self.battery is None:
            return
        power_w = getattr(self.battery.power_w, f"{phase}_w")
        steps = max(1, math.ceil(duration_s / DRAW_STEP_S))
        for _ in range(steps):
            v.pack = discharge(self.battery.pack, v.pack, power_w, duration_s / steps)


def full_pack(battery: VehicleBattery | None) -> BatteryState:
    """A fresh pack (a placeholder when the day runs without batteries)."""
    return BatteryState() if battery is None else full(battery.pack)


def without_costs(config: CoreConfig) -> CoreConfig:
    """The same day's policy with no battery and no sheet to change: the peer."""
    return replace(config, batteries=(), boards=())

"""What one vehicle does, decided in pure code: commands and ticks in, setpoints and reports out.

The service (``vehicle_agent/service.py``) feeds a :class:`JobRunner` with the orchestrator's
commands, the orchestrator's presence and one backend snapshot per control period, and carries out
the :class:`TickActions` it returns. Nothing here reads a clock or touches the network.

Life of a job (``VehicleStatus.state``)::

    idle -> taking_off -> writing -> returning -> landing -> idle
            (plan on the ground, climb, transit, settle)   (to hover above home, then land)

The plan is made before take-off and checked against the vehicle's geofence: a plan that leaves it
is refused (``failed``, code ``geofence``) and the vehicle never leaves the ground. Before writing
the vehicle must hold the start of the plan (``safety.settle_*``); if it cannot after its
approaches the job goes back to the queue (code ``not_settled``) and the brush never goes down.

Interruptions while a job is running lift the brush first (straight up to the pen-up height), then:
cancel -> return and land -> idle; operator land -> return and land -> landed; estop -> motors off,
``fault``. Losing the orchestrator interrupts nothing: only it assigns jobs and it keeps them, so
the vehicle flies its job on, and the job lease (``vehicle_agent/lease.py``, applied by the
service) decides how long it may write unheard; the brush goes down only while the lease is fresh
(``may_begin_writing``). A vehicle fault reported by the backend ends in ``fault`` as well.

Safety aborts (:class:`vehicle_agent.safety.guard.SafetyGuard`), with an alert event each: a
tracking error above the bound for longer than its window (``deviation``) lifts the brush from
where the vehicle is, then holds or returns and lands (``safety.abort_policy``); a vehicle found
outside its geofence (``geofence``) holds ``fence_hold_s`` and lands where it is, then stays in
``fault``. The job is reported ``failed`` with that code, handed back to the queue
(``retry_after_s``) while writing had not begun, final once it had: then the report waits for the
metrics of what was flown (``TickActions.aborted``). After an abort the vehicle takes no job for
``safety.abort_backoff_s``.

Reports: ``started``, ``progress`` and, for a job flown to its end, the service's result report
(``done`` only within the writing bounds); ``failed`` when the job cannot be planned, or with
``retry_after_s`` when the vehicle refused to take off (pre-arm checks). An interrupted or
stopped job (a cancel, a land, an emergency stop, a fault, the job given up on its lease:
:meth:`JobRunner.give_up`) is abandoned with no result: the status drops its ``job_id`` at once,
and the orchestrator, which asked for the interruption or was away, puts the job back in the
queue for another vehicle (or cancels it); an ``ended`` report only tells it what was written
(``vehicle_agent/end_reasons.py``). Whatever breaks a job off after its writing began (an
abort, an interruption, a stop), what was flown of it goes out in ``TickActions.aborted``: the
service measures it against the whole plan, keeps its files as a finished job's and sends its
report (the abort's ``failed``, else ``ended``); before, an ``ended`` report that nothing was
written goes out at once.
"""

from __future__ import annotations

from bus.messages import (
    CommandReply,
    ErrorInfo,
    JobAssignment,
    VehicleCommand,
)
from vehicle_agent.backends.base import Vec3, VehicleSnapshot
from vehicle_agent.end_reasons import GIVEN_UP
from vehicle_agent.preflight import PreflightReadings, preflight_problem
from vehicle_agent.runner_io import (
    ACTIVE_PHASES,
    BackendCommand,
    PreparedJob,
    RunnerConfig,
    TickActions,
    done_report,
    refuse,
    takeoff_refused_report,
)
from vehicle_agent.runner_job import RunningJob
from vehicle_agent.runner_phases import ABORT_LIFT_M, Level, RunnerPhases
from vehicle_agent.safety.guard import Breach

PREFLIGHT_HOLD_S = 30.0
"""How long in [s] a vehicle with a planned job waits for its autopilot's pre-arm checks before
it hands the job back for another vehicle. PX4 SIH on mocap flips its velocity-innovation check
on and off every few seconds on the ground (EKF2's test ratio 0.05-0.6 against its 0.5, measured
here): the vehicle takes off in the first moment it passes, usually within seconds."""

__all__ = [
    "ACTIVE_PHASES",
    "BackendCommand",
    "JobRunner",
    "PreparedJob",
    "RunnerConfig",
    "TickActions",
    "done_report",
]


class JobRunner(RunnerPhases):
    """The decision logic of one vehicle agent (see the module docstring)."""

    # --- inputs --------------------------------------------------------------------------------
    @property
    def orchestrator_alive(self) -> bool:
        return self._orchestrator_alive

    def handle_command(self, command: VehicleCommand, now_s: float) -> CommandReply:
        """Answer an orchestrator command; any motion it needs starts at the next tick."""
        if command.command == "assign":
            return self._assign(command.job, now_s)
        if command.command == "cancel":
            return self._cancel(command.job_id)
        if command.command == "land":
            return self._land()
        if command.command == "estop":
            return self._estop()
        return refuse("invalid", f"the job runner does not take {command.command!r}")

    def set_orchestrator_alive(self, alive: bool, now_s: float) -> None:
        """The orchestrator's liveliness token appeared (True) or disappeared (False): said in
        the status message; the job goes on (see the module docstring)."""
        if alive == self._orchestrator_alive:
            return
        self._orchestrator_alive = alive
        if self.phase in ACTIVE_PHASES:
            self.message = "orchestrator back" if alive else "orchestrator away: flying on"

    def plan_ready(self, prepared: PreparedJob) -> None:
        """The planner finished the current job's trajectory: checked against the geofence, then
        the vehicle takes off (or goes on, if it is already in the air)."""
        job = self._job
        if job is None or job.job_id != prepared.job_id or self._abort:
            return
        flown = (prepared.command_samples or prepared.samples).position_m_enu
        why = self.guard.check_plan(flown, self.config.hover_home_m_enu)
        if why is not None:
            self._event("alert", "geofence", f"plan of {job.job_id} refused: {why}")
            self.plan_failed(job.job_id, ErrorInfo(code="geofence", message=f"refused: {why}"))
            return
        job.prepared = prepared
        self._planned_at_s = self._now_s
        self._take_off_when_ready()

    def _take_off_when_ready(self) -> None:
        """With the plan in hand, on the ground: take off as soon as the vehicle says it can
        (its pre-arm checks pass); a vehicle that has not said so ``PREFLIGHT_HOLD_S`` after the
        plan was ready hands the job back for another."""
        job = self._job
        if self.phase != "preflight" or job is None or job.prepared is None:
            return
        if self.preflight is None:
            self._backend_command = ("takeoff", self.config.hover_home_m_enu)
            self.phase = "climb"
        elif self._now_s - self._planned_at_s > PREFLIGHT_HOLD_S:
            self.phase = "climb"  # as if refused: the same hand-back and back-off
            self.takeoff_refused(f"pre-arm checks failing for {PREFLIGHT_HOLD_S:.0f} s: "
                                 f"{self.preflight}", self._now_s)  # fmt: skip

    def plan_failed(self, job_id: str, error: ErrorInfo) -> None:
        """The job could not be laid out, planned or fenced: report it failed and come back."""
        job = self._job
        if job is None or job.job_id != job_id or self._abort:
            return
        self._reports.append(job.report(self.config.vehicle_id, "failed", error=error))
        self.message = f"cannot plan: {error.message}"
        self._job = None
        if self.phase == "preflight":
            self.state, self.phase = self._after_landing, "ground"
            return
        self._abort = "plan_failed"
        if self.phase in ("wait_plan", "transit", "settle"):
            self._start_return(self._current_reference())

    def takeoff_refused(self, reason: str, now_s: float, *, not_ready: bool = False) -> None:
        """The vehicle declined to take off (its pre-arm checks failed) and is still on the ground,
        healthy: hand the job back (``failed`` with ``retry_after_s``) and take no job for a
        while, twice as long after each refusal in a row. ``not_ready``: nothing was asked of
        the autopilot (its checks began failing just before): wait for them again instead,
        within ``PREFLIGHT_HOLD_S`` of the plan."""
        if self.phase != "climb":
            return
        if not_ready and now_s - self._planned_at_s <= PREFLIGHT_HOLD_S:
            self.phase, self.preflight = "preflight", self.preflight or reason
            return
        backoff = self._retry_backoff_s
        self._retry_backoff_s = min(2.0 * backoff, self.config.takeoff_retry_max_s)
        self._retry_at_s, self._retry_code = now_s + backoff, "takeoff_refused"
        self._retry_reason = f"take-off refused: {reason}"
        if self._job is not None and self._abort is None:
            job_id = self._job.job_id
            vid = self.config.vehicle_id
            self._reports.append(takeoff_refused_report(vid, job_id, reason, backoff))
        self.state, self.phase = self._after_landing, "ground"
        self.message = f"take-off refused: {reason} (next try in {backoff:.0f} s)"
        self._job, self._abort, self._move = None, None, None
        self._backend_command = None

    # --- commands ------------------------------------------------------------------------------
    def _assign(self, job: JobAssignment | None, now_s: float) -> CommandReply:
        if job is None:
            return refuse("missing_job", "assign needs a job")
        if self._job is not None and self._job.job_id == job.job_id:
            return CommandReply(ok=True, message="already working on it")
        if self.phase != "ground" or self.state not in ("idle", "landed"):
            return refuse("busy", f"vehicle is {self.state}", field="job")
        if now_s < self._retry_at_s:
            wait_s = self._retry_at_s - now_s
            reason = f"{self._retry_reason}; {wait_s:.0f} s to wait"
            return refuse(self._retry_code, reason, field="job")
        self._orchestrator_alive = True
        self._job = RunningJob(assignment=job)
        self._abort = None
        self._after_landing = "idle"
        self.guard.reset()
        self.state, self.phase, self.message = "taking_off", "preflight", f"job {job.job_id}"
        return CommandReply(ok=True, message=f"took job {job.job_id}")

    def _cancel(self, job_id: str | None) -> CommandReply:
        if self._job is None or (job_id is not None and job_id != self.job_id):
            return CommandReply(ok=True, message="no such job running here")
        job_id = self.job_id
        if self.phase in ACTIVE_PHASES:
            self._interrupt("cancelled", "job cancelled: returning home")
        return CommandReply(ok=True, message=f"cancelled {job_id}")

    def give_up(self) -> None:
        """Stop the job on its lease (``vehicle_agent/job_guard.py``): as a cancel does, its
        end said ``given_up`` (``vehicle_agent/end_reasons.py``)."""
        if self._job is not None and self.phase in ACTIVE_PHASES:
            self._interrupt(GIVEN_UP, f"gave {self.job_id} up: returning home")

    def _land(self) -> CommandReply:
        if self.phase == "stopped":
            return refuse("stopped", "vehicle is stopped")
        if self.phase in ("land", "fence_hold"):
            return CommandReply(ok=True, message="landing already")
        self._after_landing = "landed"
        if self.phase == "ground":
            self.state, self.message = "landed", "landed by operator"
        elif self.phase in ACTIVE_PHASES:
            self._interrupt("landed_by_operator", "landing on operator command")
        elif self.phase == "hover":
            self._start_return(self._current_reference())
        return CommandReply(ok=True, message="landing")

    def _estop(self) -> CommandReply:
        self._backend_command = ("estop", None)
        self._stop("estop", "emergency stop")
        return CommandReply(ok=True, message="motors off")

    def _stop(self, reason: str, message: str) -> None:
        if self._job is not None:
            self._end_job(self._job, reason)
        self.state, self.phase, self.message = "fault", "stopped", message
        self._move = None
        self._job = None

    # --- interruptions and aborts --------------------------------------------------------------
    def _interrupt(self, reason: str, message: str) -> None:
        """Stop writing the current job: lift the brush; what follows depends on ``reason``."""
        self._abort = reason
        self.message = message
        if self._job is not None:
            self._end_job(self._job, reason)
        self._job = None  # abandoned: the orchestrator requeues it (it asked, or it was gone)
        if self.phase == "preflight":  # never left the ground
            self.state, self.phase, self._abort = self._after_landing, "ground", None
            return
        if self.phase == "climb":
            return  # lifted already; _advance decides once the climb is over
        self._lift(self._current_reference())

    def _abort_job(
        self, code: str, message: str, lift_from: Vec3, *, level: Level = "alert"
    ) -> None:
        """A safety abort: report the job, raise an event, lift the brush, back off."""
        vid, safety = self.config.vehicle_id, self.safety
        job = self._job
        self._event(level, code, f"{vid}: {message}")
        if job is not None:
            self._end_job(job, code, job.aborted(vid, code, message, safety.abort_backoff_s))
        self._retry_at_s, self._retry_code = self._now_s + safety.abort_backoff_s, code
        self._retry_reason = f"{code} abort: {message}"
        self._abort, self._job = code, None
        self.message = f"{code}: {message}"
        self._lift(lift_from, extra_m=ABORT_LIFT_M)

    def _fence_breach(self, breach: Breach) -> None:
        """Outside the geofence: stop writing where it is, hold, then land there; ``fault``."""
        vid, job = self.config.vehicle_id, self._job
        self._event("alert", "geofence", f"{vid}: {breach.message}: holding, then landing")
        if job is not None:
            report = job.aborted(vid, "geofence", breach.message, self.safety.abort_backoff_s)
            self._end_job(job, "geofence", report)
        self._abort, self._job, self._move = "geofence", None, None
        self._after_landing = "fault"
        self.message = f"geofence: {breach.message}; landing where it is"
        self._hold_m_enu = breach.position_m_enu
        self._hover_until_s = self._now_s + self.safety.fence_hold_s
        self.phase, self.state = "fence_hold", "landing"

    # --- the tick ------------------------------------------------------------------------------
    def step(self, snapshot: VehicleSnapshot, now_s: float) -> TickActions:
        """Decide this control period from the vehicle state at its start (agent time ``now_s``)."""
        self._now_s = now_s
        self._watch(snapshot)
        if snapshot.fault is not None and self.phase != "stopped":
            self._stop("vehicle_fault", f"vehicle fault: {snapshot.fault}")
        self._take_off_when_ready()  # after the fault check: a faulted vehicle has no job
        plan_request = self._take_plan_request()
        breach = self.guard.check(self.phase, snapshot, self._tracked, now_s)
        if breach is not None and breach.code == "geofence":
            self._fence_breach(breach)
        elif breach is not None:
            self._abort_job(breach.code, breach.message, breach.position_m_enu)
        finished = None
        setpoint = self._advance(snapshot, now_s)
        if self.phase == "write" and self._job is not None:
            assert setpoint is not None
            finished = self._write_tick(snapshot, now_s, setpoint)
        self._tracked = setpoint
        if setpoint is not None:
            self._last_setpoint = setpoint
        actions = TickActions(
            backend_command=self._backend_command,
            setpoint=setpoint,
            plan_request=plan_request,
            reports=tuple(self._reports),
            telemetry=self._telemetry(snapshot, setpoint, now_s),
            finished=finished,
            aborted=self._aborted,
            events=tuple(self._events),
        )
        self._backend_command = None
        self._reports, self._events, self._aborted = [], [], None
        return actions

    def _watch(self, snap: VehicleSnapshot) -> None:
        """Events for the autopilot's mode changes, a fault appearing, its pre-arm checks."""
        vid = self.config.vehicle_id
        mode = snap.autopilot_mode
        if mode is not None and mode != self._seen_mode:
            was = "" if self._seen_mode is None else f"{self._seen_mode} -> "
            self._event("info", "vehicle_mode", f"{vid} autopilot mode {was}{mode}")
            self._seen_mode = mode
        if snap.fault != self._seen_fault:
            if snap.fault is not None:
                self._event("alert", "vehicle_fault", f"{vid} fault: {snap.fault}")
            self._seen_fault = snap.fault
        preflight = self._preflight_of(snap)
        if (preflight is None) != (self.preflight is None):
            self._preflight_event(preflight)
        self.preflight = preflight

    def _preflight_of(self, snap: VehicleSnapshot) -> str | None:
        """Why the vehicle may not take off now: on the ground between jobs or about to take
        off, the agent's preflight (``vehicle_agent/preflight.py``), which ends with the
        autopilot's own pre-arm checks; otherwise those alone."""
        limits = self.config.preflight
        if limits is None or self.phase not in ("ground", "preflight") or not snap.on_ground:
            return snap.preflight
        readings = PreflightReadings(
            health=snap.health,
            battery_fraction=snap.battery_fraction,
            has_fence=self.safety.fence is not None,
            clock_offset_s=self.clock_offset_s,
            autopilot=snap.preflight,
        )
        return preflight_problem(readings, limits)

    def _preflight_event(self, preflight: str | None) -> None:
        """One event when the preflight begins to fail (``preflight``: why) and one when it
        passes again (None), with how long the vehicle waited: the log shows how long vehicles
        wait for their checks."""
        vid = self.config.vehicle_id
        if preflight is None:
            waited_s = self._now_s - self._preflight_since_s
            self._event("info", "preflight", f"{vid} preflight passes after {waited_s:.0f} s")
        else:
            self._preflight_since_s = self._now_s
            self._event("warning", "preflight", f"{vid} held by its preflight: {preflight}")

    def _take_plan_request(self) -> JobAssignment | None:
        if self._job is None or self._job.plan_requested or self.phase == "stopped":
            return None
        self._job.plan_requested = True
        return self._job.assignment

"""An agent's job runner and the sim backend of a show's vehicle, run in one process without a
bus: the live path of a vehicle kind (phases, plan, closed loop, metrics, verdict), tick by tick."""

from __future__ import annotations

from dataclasses import dataclass, field

from bus.messages import AgentReport, JobAssignment, Telemetry, VehicleCommand
from bus.rpc import error_info_from_exception
from planner.errors import PlannerError
from showfile import Show
from vehicle_agent.backends.sim import SimVehicle
from vehicle_agent.job_runner import JobRunner
from vehicle_agent.jobs import job_metrics, prepare_job
from vehicle_agent.runner_io import PreparedJob, result_report
from vehicle_agent.setup import VehicleSetup, on_board, vehicle_setup
from vehicle_agent.trace import JobTrace


@dataclass
class LiveRun:
    """One vehicle of ``show`` writing the jobs it is given, in agent time."""

    show: Show
    vehicle_id: str
    setup: VehicleSetup = field(init=False)
    runner: JobRunner = field(init=False)
    vehicle: SimVehicle = field(init=False)
    prepared: dict[str, PreparedJob] = field(default_factory=dict)
    reports: list[AgentReport] = field(default_factory=list)
    telemetry: list[Telemetry] = field(default_factory=list)
    finished: list[JobTrace] = field(default_factory=list)
    phases: list[str] = field(default_factory=list)
    ticks: int = 0

    def __post_init__(self) -> None:
        self.setup = vehicle_setup(self.show, self.vehicle_id, time_scale=1.0)
        self.runner = JobRunner(self.setup.runner_config)
        self.runner.set_orchestrator_alive(True, 0.0)
        home = self.show.vehicle(self.vehicle_id).home_m_enu
        self.vehicle = SimVehicle(
            home,
            kind=self.setup.kind,
            settings=self.setup.settings,
            contact_region=on_board(self.setup),
        )

    @property
    def now_s(self) -> float:
        return self.ticks * self.vehicle.dt_s

    def assign(self, job: JobAssignment) -> bool:
        command = VehicleCommand(command="assign", job=job)
        return self.runner.handle_command(command, self.now_s).ok

    def tick(self) -> None:
        snap = self.vehicle.snapshot()
        actions = self.runner.step(snap, self.now_s)
        if actions.backend_command is not None:
            name, hover = actions.backend_command
            getattr(self.vehicle, name)(*(() if hover is None else (hover,)))
        if actions.plan_request is not None:
            self._plan(actions.plan_request)
        self.reports += actions.reports
        if actions.telemetry is not None:
            self.telemetry.append(actions.telemetry)
        if actions.finished is not None:
            trace = actions.finished
            self.finished.append(trace)
            metrics = job_metrics(self.setup, self.prepared[trace.job_id], trace)
            bounds = self.setup.runner_config.safety.writing
            self.reports.append(result_report(self.vehicle_id, trace, metrics, bounds))
        if not self.phases or self.phases[-1] != self.runner.phase:
            self.phases.append(self.runner.phase)
        self.vehicle.tick(actions.setpoint)
        self.ticks += 1

    def _plan(self, assignment: JobAssignment) -> None:
        """As the agent's service: plan, or report why it cannot."""
        try:
            prepared = prepare_job(self.setup, assignment)
        except PlannerError as exc:
            self.runner.plan_failed(assignment.job_id, error_info_from_exception(exc))
            return
        self.prepared[prepared.job_id] = prepared
        self.runner.plan_ready(prepared)

    def until_back(self, max_s: float) -> None:
        """Tick until the job is over and the vehicle is back at rest (or ``max_s`` passed)."""
        while self.now_s < max_s:
            self.tick()
            at_rest = self.runner.phase in ("ground", "stopped") and self.runner.job_id is None
            if at_rest and len(self.phases) > 1:
                return

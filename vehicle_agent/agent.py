"""One vehicle of a show, set up from the show file: layout, planning, metrics, backend, service.

Pure apart from :func:`run_agent` (the process entry point used by ``skyquill agent``):
:func:`vehicle_setup` reads the show once; :func:`prepare_job` turns an assignment into a planned
reference on this vehicle's board; :func:`job_metrics` measures a flown job.
"""

from __future__ import annotations

import asyncio
import importlib
import json
import logging
import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import msgspec
import numpy as np

from bus.messages import JobAssignment, JobMetrics
from planner.board import BoardFrame
from planner.errors import PlannerError
from planner.glyphs import Glyph, fit_to_area, parse_strokes_json, text_glyph
from planner.pipeline import PlanOptions, plan_strokes
from planner.samples import TrajectorySamples
from showfile import Show
from showfile.checks import footprint
from showfile.planning import board_frame, plan_options
from sim.params import BrushParams, WorldParams
from trust.settings import session_settings
from vehicle_agent.backends.base import Vec3, VehicleBackend
from vehicle_agent.backends.sim import SimBackend, SimVehicle
from vehicle_agent.control.controller import (
    DEFAULT_CONFIG,
    PAPER_CONFIG,
    ControllerConfig,
    body_reference,
)
from vehicle_agent.flight import FlightLog
from vehicle_agent.job_picture import PICTURE_NAME, PictureWorker, job_figure, save_png
from vehicle_agent.job_runner import JobRunner, PreparedJob, RunnerConfig
from vehicle_agent.metrics import flight_metrics
from vehicle_agent.safety import DeviationLimit, SafetyLimits, WritingBounds, vehicle_fence
from vehicle_agent.service import (
    AgentService,
    EventOutbox,
    ServiceSettings,
    run_until_signalled,
)
from vehicle_agent.trace import FlownTrace
from vehicle_agent.written_ink import written_ink_of_trace

LOSS_LAND_AFTER_S = 10.0
"""Agent time in [s] a vehicle hovers after losing the orchestrator before it lands."""
TELEMETRY_RATE_HZ = 20.0
"""Telemetry messages per second of wall time."""
PROGRESS_PERIOD_S = 1.0
"""Wall time in [s] between progress reports while writing."""
METRICS_PIXEL_M = 0.002
"""Pixel size in [m] of the ink rasters compared for the IoU (2 mm: cheap for 1 m characters)."""
PICTURE_WAIT_S = 3.0
"""On shutdown, how long in [s] the agent waits for a job's report.png still being drawn."""


@dataclass(frozen=True)
class VehicleSetup:
    """Everything about one vehicle of a show, derived from the show file once."""

    show: Show
    """The validated show."""
    vehicle_id: str
    """This vehicle."""
    board_frame: BoardFrame
    """Its board's pose."""
    writing_area_m: tuple[float, float]
    """Width and height in [m] of the area glyphs are fitted to."""
    margin_m: float
    """Margin in [m] kept free inside the writing area."""
    plan_options: PlanOptions
    """Planner options: limits, board, heights, solver."""
    runner_config: RunnerConfig
    """The job runner's configuration."""
    time_scale: float
    """Agent seconds per wall second."""
    control_rate_hz: float
    """Control loop rate in [Hz]."""


def vehicle_setup(show: Show, vehicle_id: str, *, time_scale: float | None = None) -> VehicleSetup:
    """The setup of ``vehicle_id`` in ``show`` (KeyError naming the known ids if absent).

    ``time_scale`` (default: the show's) applies to simulated vehicles only."""
    vehicle = show.vehicle(vehicle_id)
    board = show.board(vehicle.board)
    limits = show.vehicle_limits(vehicle_id)
    planning = show.planning
    scale = float(time_scale if time_scale is not None else show.time_scale)
    if vehicle.backend != "sim":
        scale = 1.0  # an autopilot lives in real time
    frame = board_frame(board)
    options = plan_options(planning, limits, frame)
    cruise_z_m = frame.surface_z_m + planning.write_height_m + planning.clearance_m
    runner = RunnerConfig(
        vehicle_id=vehicle.id,
        kind=vehicle.kind,
        board_id=board.id,
        home_m_enu=vehicle.home_m_enu,
        cruise_z_m=cruise_z_m,
        v_max_mps=limits.v_max_mps,
        a_max_mps2=min(limits.a_max_mps2),
        loss_land_after_s=LOSS_LAND_AFTER_S,
        telemetry_period_s=scale / TELEMETRY_RATE_HZ,
        progress_period_s=scale * PROGRESS_PERIOD_S,
        safety=safety_limits(show, vehicle_id, cruise_z_m),
    )
    return VehicleSetup(
        show=show,
        vehicle_id=vehicle.id,
        board_frame=frame,
        writing_area_m=board.writing_area_m,
        margin_m=planning.margin_m,
        plan_options=options,
        runner_config=runner,
        time_scale=scale,
        control_rate_hz=show.controller.rate_hz,
    )


def safety_limits(show: Show, vehicle_id: str, cruise_z_m: float) -> SafetyLimits:
    """The show's ``safety`` section for one vehicle, with its geofence: its board, its home and
    the transit between them, up to ``cruise_z_m`` plus the ceiling margin."""
    s = show.safety
    vehicle = show.vehicle(vehicle_id)
    fence = vehicle_fence(
        footprint(show.board(vehicle.board)),
        vehicle.home_m_enu,
        cruise_z_m,
        margin_m=s.fence_margin_m,
        ceiling_margin_m=s.fence_ceiling_margin_m,
    )
    return SafetyLimits(
        deviation=DeviationLimit(s.deviation_bound_m, s.deviation_window_s),
        fence=fence,
        writing=WritingBounds(s.rmse_pen_down_max_m, s.iou_min),
        abort_policy=s.abort_policy,
        abort_hold_s=s.abort_hold_s,
        abort_backoff_s=s.abort_backoff_s,
        fence_hold_s=s.fence_hold_s,
        settle_tolerance_m=s.settle_tolerance_m,
        settle_timeout_s=s.settle_timeout_s,
        settle_attempts=s.settle_attempts,
    )


def job_glyph(assignment: JobAssignment) -> Glyph:
    """The glyph of a job: its typed text, or its strokes document."""
    if (assignment.text is None) == (assignment.strokes is None):
        raise PlannerError("a job needs exactly one of text and strokes", field="text")
    if assignment.text is not None:
        return text_glyph(assignment.text)
    assert assignment.strokes is not None
    return parse_strokes_json(assignment.strokes, source_name=f"job {assignment.job_id}")


@dataclass(frozen=True)
class JobLayout:
    """What the metrics of a job compare against: the glyph as laid out on the board."""

    strokes_board_m: tuple[np.ndarray, ...]
    """Strokes in board-local metres, centred on the writing area."""
    planned_duration_s: float
    """Duration of the planned trajectory in [s]."""


def prepare_job(setup: VehicleSetup, assignment: JobAssignment) -> PreparedJob:
    """Lay the job's glyph out on the board and plan it (raises PlannerError)."""
    glyph = job_glyph(assignment)
    width_m, height_m = setup.writing_area_m
    fitted = fit_to_area(glyph, width_m=width_m, height_m=height_m, margin_m=setup.margin_m)
    plan = plan_strokes(list(fitted.strokes), setup.plan_options)
    samples = plan.sample(setup.plan_options.sample_rate_hz)
    layout = JobLayout(strokes_board_m=fitted.strokes, planned_duration_s=plan.duration_s)
    commands = command_samples(samples, controller_config(setup))
    return PreparedJob(assignment.job_id, samples, command_samples=commands, context=layout)


def command_samples(samples: TrajectorySamples, config: ControllerConfig) -> TrajectorySamples:
    """The vehicle reference that puts the brush tip on ``samples``, with the acceleration
    feed-forward led by the inner loop's lag: the same preprocessing ``flight.Flight`` applies
    (:func:`vehicle_agent.control.controller.body_reference`), so agent and batch flights fly the
    same."""
    dt_s = float(np.mean(np.diff(samples.t_s)))
    p, v, a = body_reference(
        config,
        samples.position_m_enu,
        samples.velocity_mps_enu,
        samples.acceleration_mps2_enu,
        dt_s,
    )
    return TrajectorySamples(samples.t_s, p, v, a, samples.pen_down)


def job_metrics(setup: VehicleSetup, prepared: PreparedJob, trace: FlownTrace) -> JobMetrics:
    """The SIM helper's flight metrics of the flown job (writing-point errors, ink IoU); for a
    backend that does not know its brush, errors of the vehicle reference point and no IoU."""
    log = flight_log(setup, trace)
    if log is None:
        error = np.linalg.norm(trace.position_m_enu - trace.reference_m_enu, axis=1)
        down = trace.pen_down
        return JobMetrics(
            rmse_pen_down_m=float(np.sqrt(np.mean(error[down] ** 2))) if down.any() else 0.0,
            rmse_m=float(np.sqrt(np.mean(error**2))) if error.size else 0.0,
            max_error_m=float(error.max()) if error.size else 0.0,
            iou=None,
            duration_s=trace.duration_s,
        )
    scores = flight_metrics(log, pixel_m=METRICS_PIXEL_M)
    return JobMetrics(
        rmse_pen_down_m=scores.rmse_pen_down_m,
        rmse_m=scores.rmse_m,
        max_error_m=scores.max_error_m,
        iou=scores.iou if math.isfinite(scores.iou) else None,
        duration_s=trace.duration_s,
        written=written_ink_of_trace(trace, setup.board_frame.to_board, setup.writing_area_m),
    )


def flight_log(setup: VehicleSetup, trace: FlownTrace) -> FlightLog | None:
    """The trace as the SIM helper's one-vehicle flight log (None without brush data)."""
    tip, width, contact = trace.pen_tip_m_enu, trace.pen_width_m, trace.pen_contact
    if tip is None or width is None or contact is None:
        return None
    axis = trace.position_m_enu - tip
    body_z = axis / np.maximum(np.linalg.norm(axis, axis=1, keepdims=True), 1e-9)
    k = trace.t_s.shape[0]
    zeros3 = np.zeros((k, 1, 3))
    return FlightLog(
        t_s=trace.t_s,
        reference_position_m_enu=trace.reference_m_enu[:, None, :],
        reference_velocity_mps_enu=zeros3,
        pen_down=trace.pen_down[:, None],
        position_m_enu=trace.position_m_enu[:, None, :],
        velocity_mps_enu=trace.velocity_mps_enu[:, None, :],
        body_z_enu=body_z[:, None, :],
        tip_m_enu=tip[:, None, :],
        brush_width_m=width[:, None],
        brush_contact=contact[:, None],
        accel_cmd_mps2_enu=zeros3,
        throttle=np.zeros((k, 1)),
        thrust_mps2=np.zeros((k, 1)),
        wind_mps_enu=zeros3,
        disturbance_estimate_mps2_enu=zeros3,
        brush_lever_m=setup.plan_options.write_height_m,
        nominal_width_m=world_params(setup).brush.nominal_width_m,
        board_height_m=setup.board_frame.surface_z_m,
    )


def job_report_dir(setup: VehicleSetup, trace: FlownTrace) -> Path:
    """Where a flown job's files go: ``<database dir>/jobs/<job>-<vehicle>-<attempt>/``."""
    name = f"{trace.job_id}-{setup.vehicle_id}-{trace.attempt}"
    return setup.show.database_path.parent / "jobs" / name


def write_job_report(
    setup: VehicleSetup, prepared: PreparedJob, trace: FlownTrace, metrics: JobMetrics | None
) -> Path:
    """Write ``metrics.json``, ``TRAJ.json`` (the planned reference) and ``flight.npz`` (what was
    flown, tick by tick) of a job; returns the directory."""
    out = job_report_dir(setup, trace)
    out.mkdir(parents=True, exist_ok=True)
    summary = {
        "job_id": trace.job_id,
        "vehicle_id": setup.vehicle_id,
        "attempt": trace.attempt,
        "board_id": setup.runner_config.board_id,
        "metrics": None if metrics is None else msgspec.to_builtins(metrics),
    }
    (out / "metrics.json").write_text(json.dumps(summary, indent=2), encoding="utf-8")
    traj = {"samples": prepared.samples.to_json_dict()}
    (out / "TRAJ.json").write_text(json.dumps(traj), encoding="utf-8")
    arrays: dict[str, Any] = {
        name: value for name, value in vars(trace).items() if isinstance(value, np.ndarray)
    }
    np.savez_compressed(out / "flight.npz", allow_pickle=False, **arrays)
    return out


def write_job_picture(
    setup: VehicleSetup, prepared: PreparedJob, trace: FlownTrace, out: Path
) -> Path | None:
    """Draw ``report.png`` of a flown job into ``out`` (slow: seconds); None for a backend that
    does not know its brush (nothing to draw the writing from)."""
    flight = flight_log(setup, trace)
    if flight is None:
        return None
    layout = prepared.context if isinstance(prepared.context, JobLayout) else None
    figure = job_figure(
        flight,
        prepared.samples,
        None if layout is None else layout.strokes_board_m,
        setup.board_frame,
        pixel_m=METRICS_PIXEL_M,
        title=f"job {trace.job_id} on {setup.vehicle_id}, attempt {trace.attempt}",
    )
    path = out / PICTURE_NAME
    save_png(figure, path)
    return path


def archive_job(
    setup: VehicleSetup,
    pictures: PictureWorker,
    prepared: PreparedJob,
    trace: FlownTrace,
    metrics: JobMetrics | None,
) -> Path:
    """:func:`write_job_report`, then ``report.png`` drawn by ``pictures`` in the background."""
    out = write_job_report(setup, prepared, trace, metrics)
    pictures.submit(lambda: write_job_picture(setup, prepared, trace, out))
    return out


def controller_config(setup: VehicleSetup) -> ControllerConfig:
    """The position controller of the show's preset, aiming the brush at this show's height."""
    if setup.show.controller.preset == "paper":
        return PAPER_CONFIG
    return replace(DEFAULT_CONFIG, brush_lever_m=setup.plan_options.write_height_m)


def world_params(setup: VehicleSetup) -> WorldParams:
    """The simulated world of this vehicle: its board's height, a brush for the show's height."""
    brush = BrushParams()
    brush = replace(brush, length_m=setup.plan_options.write_height_m + brush.nominal_press_m)
    return WorldParams(
        brush=brush,
        board_height_m=setup.board_frame.surface_z_m,
        control_rate_hz=setup.control_rate_hz,
    )


def on_board(setup: VehicleSetup) -> Callable[[Vec3], bool]:
    """Whether a point's horizontal position lies over this vehicle's board."""
    board = setup.show.board(setup.show.vehicle(setup.vehicle_id).board)
    half = np.asarray(board.size_m) / 2.0

    def inside(point_m_enu: Vec3) -> bool:
        local = setup.board_frame.to_board(np.asarray([point_m_enu]))[0]
        return bool(np.all(np.abs(local) <= half))

    return inside


def make_backend(
    setup: VehicleSetup, *, seed: int = 0, on_text: Callable[[int, str], None] | None = None
) -> VehicleBackend:
    """The backend the show file names for this vehicle; ``on_text(severity, text)`` hears what
    an autopilot says (MAVLink STATUSTEXT), e.g. ``EventOutbox.autopilot_text``."""
    vehicle = setup.show.vehicle(setup.vehicle_id)
    if vehicle.backend == "sim":
        sim = SimVehicle(
            vehicle.home_m_enu,
            world=world_params(setup),
            controller=controller_config(setup),
            seed=seed,
            contact_region=on_board(setup),
        )
        return SimBackend(sim)
    mavlink = importlib.import_module("vehicle_agent.backends.mavlink")
    backend: VehicleBackend = mavlink.create_backend(setup, on_text=on_text)
    return backend


def make_runner(setup: VehicleSetup) -> JobRunner:
    """A fresh job runner for this vehicle."""
    return JobRunner(setup.runner_config)


def warm_up(setup: VehicleSetup) -> None:
    """Plan one character before joining the bus: the first plan imports and initialises the
    solvers while holding the interpreter lock, which stalled the agent's loop (and its status
    heartbeat, by which the orchestrator knows it is alive) for up to a second."""
    try:
        prepare_job(setup, JobAssignment(job_id="warm-up", text="一"))
    except Exception as exc:  # the real jobs will say what is wrong
        logging.getLogger(__name__).warning("%s: warm-up plan failed: %s", setup.vehicle_id, exc)


async def run_agent(
    setup: VehicleSetup, backend: VehicleBackend, events: EventOutbox | None = None
) -> None:
    """Run this vehicle's agent until SIGINT/SIGTERM (the ``skyquill agent`` process);
    ``events``: the outbox the backend's ``on_text`` was given."""
    vehicle = setup.show.vehicle(setup.vehicle_id)
    warm_up(setup)
    pictures = PictureWorker(setup.vehicle_id)
    settings = ServiceSettings(
        show_id=setup.show.show_id,
        zenoh=session_settings(setup.show, setup.vehicle_id),
        time_scale=setup.time_scale,
        skip_when_late=vehicle.backend != "sim",
        lost_after_s=setup.show.policy.lost_after_s,
    )
    service = AgentService(
        settings,
        make_runner(setup),
        backend,
        prepare=lambda assignment: prepare_job(setup, assignment),
        measure=lambda prepared, trace: job_metrics(setup, prepared, trace),
        archive=lambda prepared, trace, metrics: archive_job(
            setup, pictures, prepared, trace, metrics
        ),
        events=events,
    )
    await run_until_signalled(service)
    await asyncio.to_thread(pictures.wait, PICTURE_WAIT_S)


def run_agent_blocking(
    setup: VehicleSetup, backend: VehicleBackend, events: EventOutbox | None = None
) -> None:
    """:func:`run_agent` in a fresh event loop."""
    asyncio.run(run_agent(setup, backend, events))

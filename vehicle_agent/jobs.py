"""A job on one vehicle (pure apart from the files it writes): the glyph of an assignment planned
through the vehicle's kind, the metrics of what was flown, the job's files and picture."""

from __future__ import annotations

import json
from dataclasses import fields, replace
from pathlib import Path
from typing import Any

import msgspec
import numpy as np

from bus.messages import JobAssignment, JobMetrics
from bus.public_text import drawing_label
from planner.errors import PlannerError
from planner.glyphs import Glyph, parse_strokes_json, text_glyph
from planner.samples import FloatArray
from vehicle_agent.end_reasons import flown_fraction, how_it_ended
from vehicle_agent.job_files import JobFilesPolicy, compact_arrays, prune
from vehicle_agent.job_picture import PictureOrder, PictureWorker, draw_picture
from vehicle_agent.job_runner import PreparedJob
from vehicle_agent.pace import (
    PaceSettings,
    learn,
    load_model,
    model_path,
    pace_figures,
    pace_line,
    paced,
)
from vehicle_agent.setup import VehicleSetup
from vehicle_agent.trace import JobTrace
from vehicle_agent.written_ink import written_ink_of_trace
from vehicles.jobs import plan_job
from vehicles.kind import WritingPlan

TITLE_LABEL_CHARS = 40
"""A job's label in its picture's title is cut to this many characters, so that the job's id,
vehicle and attempt stay within the title's line (``vehicles.picture.TITLE_MAX_CHARS``, 160)."""


def job_glyph(assignment: JobAssignment) -> Glyph:
    """The glyph of a job: its typed text, or its strokes document."""
    if (assignment.text is None) == (assignment.strokes is None):
        raise PlannerError("a job needs exactly one of text and strokes", field="text")
    if assignment.text is not None:
        return text_glyph(assignment.text)
    assert assignment.strokes is not None
    return parse_strokes_json(assignment.strokes, source_name=f"job {assignment.job_id}")


def job_label(assignment: JobAssignment, glyph: Glyph) -> str:
    """What the job writes, for people: its typed text, or ``drawing (N strokes)`` (the
    orchestrator's ``JobState.label``)."""
    if assignment.text is not None:
        return assignment.text.strip()
    return drawing_label(len(glyph.strokes))


def prepare_job(setup: VehicleSetup, assignment: JobAssignment) -> PreparedJob:
    """Lay the job's glyph out on the vehicle's board and plan it with its kind (raises
    PlannerError); the context is the kind's :class:`vehicles.kind.WritingPlan`, the label
    :func:`job_label`."""
    glyph = job_glyph(assignment)
    plan = plan_job(setup.show, setup.vehicle_id, glyph).plan
    return prepared_job(setup, assignment.job_id, plan, label=job_label(assignment, glyph))


def planned_job(setup: VehicleSetup, assignment: JobAssignment) -> WritingPlan:
    """The kind's plan of the job's glyph on the vehicle's board (the slow part: the planner)."""
    return plan_job(setup.show, setup.vehicle_id, job_glyph(assignment)).plan


def prepared_job(
    setup: VehicleSetup, job_id: str, plan: WritingPlan, *, label: str = ""
) -> PreparedJob:
    """``plan`` ready to fly: paced to the vehicle's tracking as last identified (show
    ``planning.pace: tracking``) and the kind's command reference made of it (fast: a job
    planned long before it flies is paced with what its vehicle flew meanwhile); ``label``:
    what it writes (:attr:`PreparedJob.label`)."""
    if (pace := PaceSettings.of(setup.show)) is not None:
        plan = paced(plan, pace, load_model(model_path(setup.show, setup.vehicle_id)))
    commands = setup.kind.command_reference(plan, setup.settings)
    return PreparedJob(
        job_id,
        plan.samples,
        command_samples=commands,
        context=plan,
        force_n=plan.force_n,
        label=label,
    )


def writing_plan(prepared: PreparedJob) -> WritingPlan:
    """The kind's plan a prepared job carries."""
    if not isinstance(prepared.context, WritingPlan):
        raise TypeError(f"job {prepared.job_id} was not prepared by prepare_job")
    return prepared.context


def job_metrics(setup: VehicleSetup, prepared: PreparedJob, trace: JobTrace) -> JobMetrics:
    """The kind's metrics of the flown job (writing-point errors, ink IoU against the whole
    target however much was flown, :func:`flown_fraction` of the plan); for a backend that
    does not know its pen, errors of the vehicle reference point and no IoU. Only what was
    measured: no pen-down RMSE (None) when the pen never came down, no figure of ``extra``
    that is not finite. A paced job's figures (``pace_*``) are added and, flown to its end, it
    refits the vehicle's tracking with the error the metrics measured at each tick."""
    metrics, error_m = _measured(setup, prepared, trace)
    metrics = msgspec.structs.replace(
        metrics,
        extra={name: value for name, value in metrics.extra.items() if np.isfinite(value)},
        flown_fraction=flown_fraction(prepared, trace),
    )
    plan = writing_plan(prepared)
    if plan.pace is None:
        return metrics
    flown = trace.flown
    whole = flown.abort_reason is None and metrics.flown_fraction >= 1.0
    if whole and error_m is not None and metrics.rmse_pen_down_m is not None:
        path = model_path(setup.show, setup.vehicle_id)
        learn(path, flown.t_s, flown.reference_m_enu, error_m, flown.pen_down, plan.pace, metrics)
    return msgspec.structs.replace(metrics, extra=metrics.extra | pace_figures(plan.pace))


def _measured(
    setup: VehicleSetup, prepared: PreparedJob, trace: JobTrace
) -> tuple[JobMetrics, FloatArray | None]:
    """The metrics and the error at each tick they were measured from (None: not known)."""
    flown = trace.flown
    if not trace.pen_known:
        error = np.linalg.norm(flown.writing_point_m_enu - flown.reference_m_enu, axis=1)
        down = flown.pen_down
        unknown_pen = JobMetrics(
            rmse_pen_down_m=float(np.sqrt(np.mean(error[down] ** 2))) if down.any() else None,
            rmse_m=float(np.sqrt(np.mean(error**2))) if error.size else 0.0,
            max_error_m=float(error.max()) if error.size else 0.0,
            iou=None,
            duration_s=trace.duration_s,
        )
        return unknown_pen, error
    score = setup.kind.score(writing_plan(prepared), flown, setup.settings)
    metrics = JobMetrics(
        rmse_pen_down_m=score.rmse_pen_down_m,
        rmse_m=score.rmse_m,
        max_error_m=score.max_error_m,
        iou=score.iou,
        duration_s=trace.duration_s,
        extra={name: float(value) for name, value in score.extra.items()},
        written=written_ink_of_trace(trace, setup.surface.to_surface, setup.writing_area_m),
    )
    return metrics, score.error_m


def job_report_dir(setup: VehicleSetup, trace: JobTrace) -> Path:
    """Where a flown job's files go: ``<database dir>/jobs/<job>-<vehicle>-<attempt>/``."""
    name = f"{trace.job_id}-{setup.vehicle_id}-{trace.attempt}"
    return setup.show.database_path.parent / "jobs" / name


def write_job_report(
    setup: VehicleSetup, prepared: PreparedJob, trace: JobTrace, metrics: JobMetrics | None
) -> Path:
    """Write ``metrics.json`` (the job, its label, why it was broken off and how far, in a
    sentence, or nulls: ``vehicle_agent/end_reasons.py``, its metrics),
    the planned reference (``TRAJ.json``) and ``flight.npz`` (what was flown, every tick:
    :func:`flight_arrays`) of a job, flown to its end or broken off; compact (the show's
    ``storage.job_files``): ``flight.npz`` alone holds both at 20 Hz in float32, the reference
    as ``reference_*``; returns the directory."""
    compact = JobFilesPolicy.of(setup.show).compact
    out = job_report_dir(setup, trace)
    out.mkdir(parents=True, exist_ok=True)
    summary = {
        "job_id": trace.job_id,
        "vehicle_id": setup.vehicle_id,
        "attempt": trace.attempt,
        "board_id": setup.runner_config.board_id,
        "label": prepared.label,
        "abort_reason": trace.flown.abort_reason,
        "ended": how_it_ended(prepared, trace),
        "metrics": None if metrics is None else msgspec.to_builtins(metrics),
    }
    (out / "metrics.json").write_text(json.dumps(summary, indent=2), encoding="utf-8")
    arrays = flight_arrays(trace)
    if compact:
        plan = prepared.samples  # its velocity and acceleration: in full detail only
        reference = {
            "t_s": plan.t_s,
            "position_m_enu": plan.position_m_enu,
            "pen_down": plan.pen_down,
        }
        arrays = compact_arrays(arrays, trace.flown.t_s) | compact_arrays(
            reference, prepared.samples.t_s, prefix="reference_"
        )
    else:
        traj = {"samples": prepared.samples.to_json_dict()}
        (out / "TRAJ.json").write_text(json.dumps(traj), encoding="utf-8")
    np.savez_compressed(out / "flight.npz", allow_pickle=False, **arrays)
    return out


def flight_arrays(trace: JobTrace) -> dict[str, Any]:
    """What ``flight.npz`` holds of a flown job: the arrays of its
    :class:`vehicles.kind.FlownWriting` under their field names (``t_s``, ``reference_m_enu``,
    ``writing_point_m_enu``, ``pen_down``, ``ink_width_m``, and ``base_m_enu``, ``force_n``
    where known), its ``extra`` entries under theirs (``velocity_mps_enu``, ``pen_contact``
    where known) and ``pen_known`` (a 0-d bool, :attr:`JobTrace.pen_known`)."""
    flown = trace.flown
    arrays: dict[str, Any] = {}
    for f in fields(flown):
        value = getattr(flown, f.name)
        if isinstance(value, np.ndarray):
            arrays[f.name] = value
    if clash := arrays.keys() & flown.extra.keys():
        raise ValueError(f"extra entries {sorted(clash)} shadow the trace's own arrays")
    return arrays | dict(flown.extra) | {"pen_known": np.asarray(trace.pen_known)}


def picture_order(
    setup: VehicleSetup, prepared: PreparedJob, trace: JobTrace
) -> PictureOrder | None:
    """What drawing ``report.png`` of a flown job needs; None for a backend that does not know
    its pen (nothing to draw the writing from)."""
    if not trace.pen_known:
        return None
    title = picture_title(setup, prepared, trace)
    plan = writing_plan(prepared)
    if plan.pace is not None:
        title += f"\n{pace_line(plan.pace)}"
    compact = JobFilesPolicy.of(setup.show).compact
    kept = replace(plan, detail=None)  # the kind's own plan object: not drawn
    return PictureOrder(setup.kind.name, setup.settings, kept, trace.flown, title, compact)


def picture_title(setup: VehicleSetup, prepared: PreparedJob, trace: JobTrace) -> str:
    """The first line of a job's picture title: what it writes (its label on one line, cut to
    :data:`TITLE_LABEL_CHARS`), which job, and how much of it was flown when it was broken off:
    ``永 · job j1 on uav1, attempt 1, cancelled at 42% of its plan``."""
    label = " ".join(prepared.label.split())
    if len(label) > TITLE_LABEL_CHARS:
        label = label[: TITLE_LABEL_CHARS - 3] + "..."
    title = f"job {trace.job_id} on {setup.vehicle_id}, attempt {trace.attempt}"
    if label:
        title = f"{label} · {title}"
    if (ended := how_it_ended(prepared, trace)) is not None:
        title += f", {ended}"
    return title


def write_job_picture(
    setup: VehicleSetup, prepared: PreparedJob, trace: JobTrace, out: Path
) -> Path | None:
    """Draw ``report.png`` of a flown job into ``out`` now (slow: about a second of CPU); None
    for a backend that does not know its pen."""
    order = picture_order(setup, prepared, trace)
    return None if order is None else draw_picture(out, order)


def archive_job(
    setup: VehicleSetup,
    pictures: PictureWorker,
    prepared: PreparedJob,
    trace: JobTrace,
    metrics: JobMetrics | None,
) -> Path:
    """:func:`write_job_report`, then ``report.png`` ordered from ``pictures`` (drawn in the
    background, later when the machine is busy); the vehicle's older job directories beyond
    its budget or age are removed."""
    out = write_job_report(setup, prepared, trace, metrics)
    prune(out.parent, setup.vehicle_id, JobFilesPolicy.of(setup.show))
    if (order := picture_order(setup, prepared, trace)) is not None:
        pictures.submit(out, order)
    return out

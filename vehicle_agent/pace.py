"""A vehicle's pace (show ``planning.pace: tracking``): its tracking model kept on disk, each
job's plan stretched to the pace the model predicts it can hold, and the model refitted on what
the job flew (planner.pace).

The model lives at ``<database dir>/tracking/<vehicle>.json``, beside the show's other durable
state: it outlives the agent (a restarted agent, or a fleet host's other planning worker, plans
with what the vehicle last flew). The file holds the fit's statistics and, for people, the
figures they give (floor, lag, bandwidth) and the last job's predicted and flown errors. It is
replaced atomically; an unreadable one is set aside as ``.bad`` and the vehicle flies its next
job at the cautious first pace, as a new vehicle does.
"""

from __future__ import annotations

import json
import logging
import math
import os
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from bus.messages import JobMetrics
from planner.pace import (
    FlightStatistics,
    PaceChoice,
    TrackingModel,
    choose_pace,
    flight_statistics,
)
from planner.samples import BoolArray, FloatArray
from showfile.models import Show
from vehicles.kind import WritingPlan

log = logging.getLogger(__name__)

FORMAT = "skyquill.tracking/1"


@dataclass(frozen=True)
class PaceSettings:
    """The show's ``planning.pace_*`` fields."""

    target_rmse_m: float
    first_stretch: float
    max_stretch: float

    @classmethod
    def of(cls, show: Show) -> PaceSettings | None:
        """The show's settings, or None when its pace is not ``tracking``."""
        planning = show.planning
        if planning.pace != "tracking":
            return None
        return cls(
            planning.pace_rmse_target_m, planning.pace_first_stretch, planning.pace_max_stretch
        )


def model_path(show: Show, vehicle_id: str) -> Path:
    """``<database dir>/tracking/<vehicle>.json`` (vehicle ids are show-file identifiers)."""
    return show.database_path.parent / "tracking" / f"{vehicle_id}.json"


def load_model(path: Path) -> TrackingModel | None:
    """The model kept at ``path``; None when there is none yet or it cannot be read (then set
    aside as ``<name>.bad``, logged)."""
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
        if doc.get("format") != FORMAT:
            raise ValueError(f"format {doc.get('format')!r}, expected {FORMAT!r}")
        stats = doc["statistics"]
        statistics = FlightStatistics(
            np.asarray(stats["gram"], dtype=np.float64).reshape(3, 3),
            np.asarray(stats["moment"], dtype=np.float64).reshape(3),
            float(stats["flights"]),
            float(stats.get("fastest_stretch", 1.0)),
        )
        if not (np.all(np.isfinite(statistics.gram)) and np.all(np.isfinite(statistics.moment))):
            raise ValueError("statistics are not finite")
    except FileNotFoundError:
        return None
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:
        log.warning("%s: unreadable tracking model (%s); flying the first pace again", path, exc)
        path.replace(path.with_name(path.name + ".bad"))
        return None
    return TrackingModel.fitted(statistics)


def save_model(path: Path, model: TrackingModel, last_job: dict[str, Any]) -> None:
    """Replace the model at ``path`` atomically (its folder made when missing)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    doc = {
        "format": FORMAT,
        "floor_mm": round(model.floor_m * 1e3, 3),
        "lag_s": round(model.lag_s, 4),
        "bandwidth_radps": round(model.bandwidth_radps, 3)
        if math.isfinite(model.bandwidth_radps)
        else None,
        "flights": round(model.statistics.flights, 3),
        "last_job": last_job,
        "statistics": {
            "gram": model.statistics.gram.tolist(),
            "moment": model.statistics.moment.tolist(),
            "flights": model.statistics.flights,
            "fastest_stretch": model.statistics.fastest_stretch,
        },
    }
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(doc, indent=2), encoding="utf-8")
    tmp.replace(path)


def paced(plan: WritingPlan, settings: PaceSettings, model: TrackingModel | None) -> WritingPlan:
    """``plan`` stretched to the pace ``model`` predicts meets the target (the first pace
    without a model), with the choice recorded on it."""
    choice = choose_pace(
        model,
        plan.samples,
        target_rmse_m=settings.target_rmse_m,
        first_stretch=settings.first_stretch,
        max_stretch=settings.max_stretch,
    )
    samples = plan.samples.stretched(choice.stretch)
    original_t_s = plan.samples.t_s * choice.stretch

    def resampled(values: Any) -> Any:
        if values is None:
            return None
        return np.interp(samples.t_s, original_t_s, np.asarray(values, dtype=np.float64))

    return replace(
        plan,
        samples=samples,
        force_n=resampled(plan.force_n),
        width_m=resampled(plan.width_m),
        pace=choice,
    )


def pace_figures(choice: PaceChoice) -> dict[str, float]:
    """A job's pace for its metrics (``extra``): the stretch, the target and the prediction."""
    figures = {"pace_stretch": choice.stretch, "pace_target_rmse_m": choice.target_rmse_m}
    if choice.predicted_rmse_m is not None:
        figures["pace_predicted_rmse_pen_down_m"] = choice.predicted_rmse_m
    return figures


def pace_line(choice: PaceChoice) -> str:
    """One line for a job's report: how much slower it flew and what was predicted of it."""
    if choice.predicted_rmse_m is None:
        return f"paced x{choice.stretch:.2f} (first job: tracking not yet identified)"
    predicted_mm, target_mm = choice.predicted_rmse_m * 1e3, choice.target_rmse_m * 1e3
    line = f"paced x{choice.stretch:.2f}: predicted {predicted_mm:.1f} mm pen-down RMSE"
    if choice.reason == "floor":
        return f"{line}, above the {target_mm:.1f} mm aimed at even this slow"
    return f"{line} (aimed at {target_mm:.1f} mm)"


def learn(
    path: Path,
    t_s: FloatArray,
    reference_m: FloatArray,
    error_m: FloatArray,
    pen_down: BoolArray,
    choice: PaceChoice,
    metrics: JobMetrics,
) -> None:
    """Refit the model at ``path`` with a job flown to its end: ``t_s`` (K,) its ticks, the
    reference (K, 3) [m] they followed, the error (K,) [m] its metrics measured and the pen;
    a job too short to teach anything leaves the model as it is."""
    flight = flight_statistics(t_s, reference_m, error_m, pen_down, choice.stretch)
    if flight is None:
        return
    model = load_model(path)
    model = TrackingModel.fitted(flight) if model is None else model.updated(flight)
    predicted, flown = choice.predicted_rmse_m, metrics.rmse_pen_down_m
    last_job = {
        "stretch": round(choice.stretch, 3),
        "predicted_rmse_mm": None if predicted is None else round(predicted * 1e3, 2),
        "flown_rmse_mm": None if flown is None else round(flown * 1e3, 2),
        "iou": metrics.iou,
    }
    save_model(path, model, last_job)

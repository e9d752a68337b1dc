"""A fixed, made-up show state: for ``skyquill tui --demo``, screenshots, tests and benchmarks.

Deterministic (no randomness, no clock): the same calls give the same screen.
"""

from __future__ import annotations

import itertools
import math
from typing import Any

from bus.messages import (
    ErrorInfo,
    Event,
    JobMetrics,
    JobState,
    JobStateName,
    ShowSnapshot,
    Telemetry,
    VehicleStatus,
    VehicleSummary,
)
from tui.inputs import OrchestratorPresence, VehiclePresence
from tui.model import ConsoleModel
from tui.settings import BoardGeometry, ConsoleSettings, VehicleSpec
from vehicles import DEFAULT_KIND

DEMO_TIME_S = 1_700_000_000.0
"""Console time of the demo state (a fixed Unix time)."""

GONG_STROKES_M = (
    ((-0.35, 0.35), (0.35, 0.35)),
    ((0.0, 0.35), (0.0, -0.35)),
    ((-0.45, -0.35), (0.45, -0.35)),
)
"""工 in board metres: three straight strokes, y up."""


def demo_settings(vehicles: int = 3) -> ConsoleSettings:
    """Boards side by side along east, one vehicle of the default kind each."""
    boards = tuple(
        BoardGeometry(f"b{i + 1}", center_m_enu=(3.0 * i, 0.0, 0.0)) for i in range(vehicles)
    )
    specs = tuple(
        VehicleSpec(f"uav{i + 1}", DEFAULT_KIND, f"b{i + 1}", "board") for i in range(vehicles)
    )
    return ConsoleSettings(show_id="demo-show", boards=boards, vehicles=specs)


def demo_mixed_settings() -> ConsoleSettings:
    """One of each kind: a brush quadrotor over a table, the hexarotor on a wall, the ground
    writer on the floor."""
    boards = (
        BoardGeometry("b1"),
        BoardGeometry("wall1", center_m_enu=(3.0, 0.0, 1.5), orientation="vertical"),
        BoardGeometry("floor1", center_m_enu=(6.0, 0.0, 0.0)),
    )
    specs = (
        VehicleSpec("uav1", "quadrotor-brush", "b1", "board"),
        VehicleSpec("hexa1", "hexarotor-sponge", "wall1", "wall"),
        VehicleSpec("rover1", "omni-wheel", "floor1", "floor"),
    )
    return ConsoleSettings(show_id="demo-mixed", boards=boards, vehicles=specs)


def demo_wall_telemetry(
    vehicle_id: str, board: BoardGeometry, job_id: str, fraction: float
) -> list[Telemetry]:
    """Telemetry of the hexarotor having written ``fraction`` of 工 on a wall ``board``: the
    sponge pressed with a force that swells mid-stroke, measured a little off its target."""
    path = glyph_path(GONG_STROKES_M)
    count = max(1, round(fraction * len(path)))
    cx, cy, cz = board.center_m_enu
    out = []
    for i, ((u, v, lift), pen_down) in enumerate(path[:count]):
        wobble = 0.004 * math.sin(0.5 * i)
        target = 3.0 + 1.5 * math.sin(0.08 * i) ** 2 if pen_down else 0.0
        measured = target + 0.25 * math.sin(0.6 * i) if pen_down else 0.0
        reference = (cx + u, cy - lift, cz + v)
        out.append(
            Telemetry(
                vehicle_id=vehicle_id,
                t_s=0.05 * i,
                state="writing",
                position_m_enu=(cx + u + wobble, cy - lift, cz + v - wobble),
                velocity_mps_enu=(0.0, 0.0, 0.0),
                reference_m_enu=reference,
                pen_down=pen_down,
                tracking_error_m=abs(wobble) * math.sqrt(2.0),
                battery_fraction=0.64,
                job_id=job_id,
                progress=(i + 1) / len(path),
                force_n=measured,
                force_reference_n=target,
            )
        )
    return out


def demo_mixed_model() -> ConsoleModel:
    """:func:`demo_model` on :func:`demo_mixed_settings`: the quadrotor and the hexarotor
    writing (the hexarotor with its force), the ground writer waiting."""
    settings = demo_mixed_settings()
    model = demo_model(settings)
    wall = settings.board("wall1")
    assert wall is not None
    now = DEMO_TIME_S
    model.apply(
        _job("j-0008", "writing", "工", 2, vehicle_id="hexa1", progress=0.4, attempts=1), now
    )
    for item in demo_wall_telemetry("hexa1", wall, "j-0008", 0.4):
        model.apply(item, now - 0.1)
    model.apply(
        VehicleStatus(
            vehicle_id="rover1",
            kind="omni-wheel",
            state="idle",
            board_id="floor1",
            battery_fraction=0.18,
            battery_minutes_left=2.5,
            preflight="battery: 18% left, at or below the 20% reserve",
            flight_s_today=2950.0,
        ),
        now - 0.2,
    )
    model.apply(VehiclePresence("rover1", alive=True), now - 0.2)
    return model


def glyph_path(
    strokes: tuple[tuple[tuple[float, float], ...], ...], step_m: float = 0.02, lift_m: float = 0.1
) -> list[tuple[tuple[float, float, float], bool]]:
    """Board-frame points ``((u, v, height), pen_down)`` along strokes with pen-up transits."""
    path: list[tuple[tuple[float, float, float], bool]] = []
    for stroke in strokes:
        if path:
            (u0, v0, _), _ = path[-1]
            u1, v1 = stroke[0]
            path.extend(_segment((u0, v0), (u1, v1), step_m, lift_m, pen_down=False))
        for a, b in itertools.pairwise(stroke):
            path.extend(_segment(a, b, step_m, 0.0, pen_down=True))
    return path


def _segment(
    a: tuple[float, float], b: tuple[float, float], step_m: float, height_m: float, pen_down: bool
) -> list[tuple[tuple[float, float, float], bool]]:
    n = max(1, math.ceil(math.dist(a, b) / step_m))
    return [
        ((a[0] + (b[0] - a[0]) * i / n, a[1] + (b[1] - a[1]) * i / n, height_m), pen_down)
        for i in range(n + 1)
    ]


def demo_telemetry(
    vehicle_id: str, board: BoardGeometry, job_id: str, fraction: float, t0_s: float = 0.0
) -> list[Telemetry]:
    """Telemetry of a vehicle having written ``fraction`` of 工 on ``board``, wobbling a bit."""
    path = glyph_path(GONG_STROKES_M)
    count = max(1, round(fraction * len(path)))
    cx, cy, cz = board.center_m_enu
    out = []
    for i, ((u, v, h), pen_down) in enumerate(path[:count]):
        wobble = 0.012 * math.sin(0.35 * i)
        reference = (cx + u, cy + v, cz + h)
        position = (cx + u + wobble, cy + v - 0.5 * wobble, cz + h)
        out.append(
            Telemetry(
                vehicle_id=vehicle_id,
                t_s=t0_s + 0.05 * i,
                state="writing",
                position_m_enu=position,
                velocity_mps_enu=(0.0, 0.0, 0.0),
                reference_m_enu=reference,
                pen_down=pen_down,
                tracking_error_m=abs(wobble) * 1.118,
                battery_fraction=0.81,
                job_id=job_id,
                progress=(i + 1) / len(path),
            )
        )
    return out


def _job(
    job_id: str, state: JobStateName, label: str, minutes_ago: float, **extra: Any
) -> JobState:
    created = DEMO_TIME_S - 60.0 * minutes_ago
    return JobState(
        job_id=job_id,
        state=state,
        label=label,
        kind="text",
        client_id="kiosk-7",
        created_at_s=created,
        updated_at_s=created + 1.0,
        **extra,
    )


def demo_jobs() -> list[JobState]:
    metrics = JobMetrics(
        rmse_pen_down_m=0.012, rmse_m=0.02, max_error_m=0.04, iou=0.83, duration_s=41.0
    )
    return [
        _job("j-0001", "done", "永", 12, vehicle_id="uav1", progress=1.0, metrics=metrics),
        _job(
            "j-0002",
            "failed",
            "龍",
            9,
            vehicle_id="uav3",
            attempts=2,
            error=ErrorInfo(code="infeasible", message="stroke 3 too fast for limits"),
        ),
        _job("j-0003", "writing", "工", 3, vehicle_id="uav1", progress=0.55, attempts=1),
        _job("j-0004", "queued", "山", 2, queue_position=1, eta_s=35.0),
        _job("j-0005", "queued", "川", 1.5, queue_position=2, eta_s=95.0),
        _job("j-0006", "awaiting_approval", "愛", 1),
        _job("j-0007", "awaiting_approval", "Hi", 0.5),
    ]


def demo_events() -> list[Event]:
    t = DEMO_TIME_S
    return [
        Event(
            time_s=t - 600,
            level="info",
            kind="vehicle_appeared",
            message="joined",
            vehicle_id="uav1",
        ),
        Event(
            time_s=t - 540, level="info", kind="job_done", message="永 RMSE 1.2 cm", job_id="j-0001"
        ),
        Event(
            time_s=t - 200,
            level="alert",
            kind="vehicle_lost",
            message="no liveliness",
            vehicle_id="uav3",
        ),
        Event(
            time_s=t - 199,
            level="warning",
            kind="job_requeued",
            message="attempt 2",
            job_id="j-0002",
        ),
        Event(
            time_s=t - 120,
            level="alert",
            kind="job_failed",
            message="stroke 3 too fast for limits",
            job_id="j-0002",
        ),
    ]


def demo_model(settings: ConsoleSettings | None = None) -> ConsoleModel:
    """A model showing one vehicle writing, one taking off, one lost, and a varied queue."""
    settings = settings or demo_settings()
    model = ConsoleModel(settings)
    now = DEMO_TIME_S
    model.apply(OrchestratorPresence(alive=True), now)
    summaries = [
        VehicleSummary(
            vehicle_id=v.vehicle_id, kind=v.kind, state="idle", alive=True, board_id=v.board_id
        )
        for v in settings.vehicles
    ]
    model.apply_snapshot(
        ShowSnapshot(
            show_id=settings.show_id,
            time_s=now,
            queue_paused=False,
            jobs=demo_jobs(),
            vehicles=summaries,
        ),
        now,
        full=True,
    )
    for event in demo_events():
        model.apply(event, now)
    specs = settings.vehicles
    board = settings.board(specs[0].board_id) if specs else None
    if board is not None:
        for item in demo_telemetry(specs[0].vehicle_id, board, "j-0003", 0.55):
            model.apply(item, now - 0.1)
    if len(specs) > 1:
        model.apply(
            VehicleStatus(
                vehicle_id=specs[1].vehicle_id,
                kind=specs[1].kind,
                state="taking_off",
                board_id=specs[1].board_id,
                link_loss_fraction=0.0,
                flight_s_today=1260.0,
            ),
            now - 0.3,
        )
    if len(specs) > 2:
        model.apply(VehiclePresence(specs[2].vehicle_id, alive=False), now - 200)
    return model

"""The brush quadrotor's flight log <-> the kinds' one trace format (:class:`FlownWriting`).

A batch flight records N vehicles in a :class:`FlightLog`; the live agent records one vehicle in a
trace. Both become a :class:`vehicles.kind.FlownWriting` (one vehicle, one row per tick), and the
metrics and the report read a one-vehicle :class:`FlightLog` rebuilt from it.
"""

from __future__ import annotations

import numpy as np

from planner.samples import TrajectorySamples
from vehicles.kind import FlownWriting
from vehicles.quadrotor_brush.flight import FlightLog
from vehicles.quadrotor_brush.metrics import writing_point_error
from vehicles.quadrotor_brush.params import BrushParams

_UP = np.array([0.0, 0.0, 1.0])


def flown_of(log: FlightLog, vehicle: int = 0) -> FlownWriting:
    """Vehicle ``vehicle`` of a batch log as a :class:`FlownWriting` (true values per tick)."""
    reference = log.reference_position_m_enu[:, vehicle]
    contact = log.brush_contact[:, vehicle]
    return FlownWriting(
        t_s=log.t_s,
        reference_m_enu=reference,
        writing_point_m_enu=reference + writing_point_error(log)[:, vehicle],
        pen_down=log.pen_down[:, vehicle],
        ink_width_m=np.where(contact, log.brush_width_m[:, vehicle], 0.0),
        base_m_enu=log.position_m_enu[:, vehicle],
        extra={
            "velocity_mps_enu": log.velocity_mps_enu[:, vehicle],
            "body_z_enu": log.body_z_enu[:, vehicle],
            "tip_m_enu": log.tip_m_enu[:, vehicle],
        },
        abort_reason=log.abort_reason,
    )


def log_of(
    flown: FlownWriting, samples: TrajectorySamples, brush: BrushParams, board_height_m: float
) -> FlightLog:
    """A one-vehicle :class:`FlightLog` of ``flown`` (what the metrics and report read);
    ``samples`` is the planned writing-point reference (its velocity is drawn in the report).

    Without a logged body axis (the live agent's trace) the brush axis from the tip up to the body
    stands for it; without a base position the writing point stands for the body."""
    k = flown.t_s.shape[0]
    base = flown.base_m_enu if flown.base_m_enu is not None else flown.writing_point_m_enu
    tip = flown.extra.get("tip_m_enu", flown.writing_point_m_enu)
    body_z = flown.extra.get("body_z_enu")
    if body_z is None:
        axis = base - tip
        length = np.linalg.norm(axis, axis=1, keepdims=True)
        body_z = np.where(length > 1e-9, axis / np.maximum(length, 1e-9), _UP)
    velocity = flown.extra.get("velocity_mps_enu", np.zeros((k, 3)))
    planned_v = np.stack(
        [np.interp(flown.t_s, samples.t_s, samples.velocity_mps_enu[:, c]) for c in range(3)],
        axis=1,
    )
    zeros3 = np.zeros((k, 1, 3))
    return FlightLog(
        t_s=flown.t_s,
        reference_position_m_enu=flown.reference_m_enu[:, None, :],
        reference_velocity_mps_enu=planned_v[:, None, :],
        pen_down=flown.pen_down[:, None],
        position_m_enu=base[:, None, :],
        velocity_mps_enu=velocity[:, None, :],
        body_z_enu=np.asarray(body_z)[:, None, :],
        tip_m_enu=tip[:, None, :],
        brush_width_m=flown.ink_width_m[:, None],
        brush_contact=(flown.ink_width_m > 0.0)[:, None],
        accel_cmd_mps2_enu=zeros3,
        throttle=np.zeros((k, 1)),
        thrust_mps2=np.zeros((k, 1)),
        wind_mps_enu=zeros3,
        disturbance_estimate_mps2_enu=zeros3,
        brush_lever_m=brush.write_height_m,
        nominal_width_m=brush.nominal_width_m,
        board_height_m=board_height_m,
        abort_reason=flown.abort_reason,
    )

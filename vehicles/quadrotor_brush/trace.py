"""The brush quadrotor's batch flight log as the kinds' one trace format (:class:`FlownWriting`).

A batch flight records N vehicles in a :class:`FlightLog` (the simulator's own record); each
vehicle of it becomes a :class:`vehicles.kind.FlownWriting` (one row per tick), the format the
metrics and the report read, as they read the live agent's.
"""

from __future__ import annotations

import numpy as np

from vehicles.kind import FlownWriting
from vehicles.quadrotor_brush.flight import FlightLog


def flown_of(log: FlightLog, vehicle: int = 0) -> FlownWriting:
    """Vehicle ``vehicle`` of a batch log as a :class:`FlownWriting` (true values per tick)."""
    reference = log.reference_position_m_enu[:, vehicle]
    contact = log.brush_contact[:, vehicle]
    return FlownWriting(
        t_s=log.t_s,
        reference_m_enu=reference,
        writing_point_m_enu=reference + log.writing_point_error()[:, vehicle],
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

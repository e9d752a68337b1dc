"""Characters written by an independent controller: RotorPy's SE3 geometric controller on PX4
SIH's quadrotor airframe (RotorPy's ``px4_sihsim_quadx`` parameters), fed the plans the agent
flies (``planning.pace: tracking``), measured and paced by the agent's own job code.

A peer for the writing rows of ``bench_mavlink.py``: a controller we did not write, on an
airframe we did not tune, writing the same plans. RotorPy simulates the rigid body, rotor
dynamics and drag (``Multirotor``, motor speeds commanded); its controller runs at the
simulation step. RotorPy has no brush: the tip is the body's point one lever below along its
axis (as the kind measures it), inking the 2 cm brush's nominal width wherever the plan puts
the pen down. The vehicle starts at rest on the plan's first point.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bus.messages import JobAssignment
from vehicle_agent.jobs import job_metrics, planned_job, prepared_job
from vehicle_agent.setup import vehicle_setup
from vehicle_agent.trace import JobTrace
from vehicles.kind import FlownWriting

SIM_RATE_HZ = 500.0
"""RotorPy's step and its controller's rate (RotorPy's own examples use 100-500 Hz)."""
RECORD_EVERY = 5
"""Steps between recorded ticks (100 Hz, the agent's control rate)."""
BRUSH_WIDTH_M = 0.02


def _flat_outputs(samples: Any) -> dict[str, np.ndarray]:
    """RotorPy's flat outputs of a sampled reference (jerk and snap differentiated)."""
    t = samples.t_s
    jerk = np.gradient(samples.acceleration_mps2_enu, t, axis=0)
    return {
        "x": samples.position_m_enu,
        "x_dot": samples.velocity_mps_enu,
        "x_ddot": samples.acceleration_mps2_enu,
        "x_dddot": jerk,
        "x_ddddot": np.gradient(jerk, t, axis=0),
    }


def _body_z(quaternion_xyzw: np.ndarray) -> np.ndarray:
    x, y, z, w = quaternion_xyzw
    return np.array([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)])


def fly_rotorpy(samples: Any, lever_m: float) -> FlownWriting:
    """Fly ``samples`` (the writing point's reference, ENU) with RotorPy's SE3 controller."""
    from rotorpy.controllers.quadrotor_control import SE3Control
    from rotorpy.vehicles.multirotor import Multirotor
    from rotorpy.vehicles.px4_sihsim_quadx_params import quad_params

    hover_radps = float(np.sqrt(quad_params["mass"] * 9.81 / (4 * quad_params["k_eta"])))
    state = {
        "x": samples.position_m_enu[0].copy(),
        "v": np.zeros(3),
        "q": np.array([0.0, 0.0, 0.0, 1.0]),
        "w": np.zeros(3),
        "wind": np.zeros(3),
        "rotor_speeds": np.full(4, hover_radps),
    }
    vehicle = Multirotor(quad_params, initial_state=state)
    controller = SE3Control(quad_params)
    flat = _flat_outputs(samples)
    dt_s = 1.0 / SIM_RATE_HZ
    steps = int(samples.duration_s * SIM_RATE_HZ)
    t_s, body, body_z, reference, pen = [], [], [], [], []
    for k in range(steps + 1):
        t = k * dt_s
        i = samples.index_at(t)
        wanted = {name: values[i] for name, values in flat.items()}
        wanted |= {"yaw": 0.0, "yaw_dot": 0.0, "yaw_ddot": 0.0}
        if k % RECORD_EVERY == 0:
            t_s.append(t)
            body.append(state["x"].copy())
            body_z.append(_body_z(state["q"]))
            reference.append(samples.position_m_enu[i])
            pen.append(bool(samples.pen_down[i]))
        state = vehicle.step(state, controller.update(t, state, wanted), dt_s)
    body_m = np.asarray(body)
    axis = np.asarray(body_z)
    tip = body_m - lever_m * axis
    down = np.asarray(pen)
    return FlownWriting(
        t_s=np.asarray(t_s),
        reference_m_enu=np.asarray(reference),
        writing_point_m_enu=tip,
        pen_down=down,
        ink_width_m=np.where(down, BRUSH_WIDTH_M, 0.0),
        base_m_enu=body_m,
        extra={"body_z_enu": axis, "tip_m_enu": tip},
    )


def write_rotorpy(show: Any, texts: list[str]) -> list[Any]:
    """Each of ``texts`` planned, paced, flown by RotorPy and measured by the agent's job code,
    one after the other on vehicle ``v1`` of ``show``: the jobs' metrics."""
    setup = vehicle_setup(show, "v1")
    lever_m = show.planning.write_height_m
    measured = []
    for k, text in enumerate(texts):
        assignment = JobAssignment(job_id=f"j{k}", text=text)
        prepared = prepared_job(setup, assignment.job_id, planned_job(setup, assignment))
        flown = fly_rotorpy(prepared.samples, lever_m)
        trace = JobTrace(assignment.job_id, 1, flown, pen_known=True)
        measured.append(job_metrics(setup, prepared, trace))
    return measured

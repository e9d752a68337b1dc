"""PX4 SIH's simulated airframe as start.py sets it up: where it starts, how noisy its IMU is,
and what PX4's estimator is told of that noise (pure; free of project imports, start.py imports
it by path)."""

from __future__ import annotations

import math
import struct

PX4_HOME_FLOAT32_STEPS = 16
"""How many float32 steps (0.4 m north, 1.4 m east here) a PX4 home may move to sit half-way
along the truth's 1e-7 degree step (:func:`px4_sih_degrees`); each vehicle simulates its own
world, anchored on its own home, and fuses the mocap in the show frame."""
PX4_VIBRATION_PARAM = "SIH_IMU_VIB"
"""SIH's armed IMU noise as a fraction of its own (added by scripts/sitl/source_edits.py)."""
SIH_STOCK_VIBRATION = 1.0
"""SIH's own IMU noise: SIH_IMU_VIB's default, and any PX4 built without our edit."""
SIH_IMU_RATE_HZ = 250.0
"""How often SIH samples its IMU (``sensor_combined`` in its ULogs, 4 ms apart)."""
EKF2_STEP_HZ = 100.0
"""EKF2's update rate (EKF2_PREDICT_US 10 ms): the gyro's samples over one step are averaged."""
EKF2_GYR_NOISE_DEFAULT = 0.015
"""PX4's EKF2_GYR_NOISE in [rad/s]: a real IMU's."""
VIBRATING_TAU_VEL_S = 0.03
"""EKF2_TAU_VEL in [s] of an airframe whose IMU is noisier than a real one's: the output predictor
integrates the accelerometer between updates, and SIH's stock one (1.7 m/s^2 a sample across the
body, ``sih.cpp``) made EKF2's velocity 30-39 mm/s RMS off the truth at the agent's 0.1 s, 22-25
at 0.03; ``shows/sitl-px4.yaml``, 12 held-out, stock airframe, quiet: 5-9 of 12 ``done`` in four
runs against 2 (issue 31, docs/sitl.md). The agent keeps a value below its own."""


def airframe_params(imu_vibration: float | None) -> dict[str, float]:
    """Boot parameters of a PX4 SIH airframe with ``imu_vibration`` (None: SIH's own noise):
    SIH_IMU_VIB when given, and where its IMU is noisier than PX4's defaults assume, EKF2's
    gyro noise (:func:`sih_gyro_noise`) and velocity time constant (:data:`VIBRATING_TAU_VEL_S`)."""
    params = {} if imu_vibration is None else {PX4_VIBRATION_PARAM: imu_vibration}
    vibration = SIH_STOCK_VIBRATION if imu_vibration is None else imu_vibration
    gyro_noise = sih_gyro_noise(vibration)
    if gyro_noise > EKF2_GYR_NOISE_DEFAULT:
        params["EKF2_GYR_NOISE"] = round(gyro_noise, 3)
        params["EKF2_TAU_VEL"] = VIBRATING_TAU_VEL_S
    return params


def sih_gyro_noise(vibration: float) -> float:
    """EKF2_GYR_NOISE in [rad/s] that describes SIH's gyro at ``vibration`` (SIH_IMU_VIB): its
    roll axis's noise a sample, 0.01 + 0.13 x vibration rad/s (``sih.cpp``, our edit of it),
    over one EKF2 step. On the stock airframe (0.089 against PX4's 0.015, for a real IMU) EKF2's
    roll had wandered 9.5 mrad RMS below 0.5 Hz off SIH's truth, 0.09 m/s^2 of sideways thrust the
    position loop chased; at 0.1 rad/s 5.1-6.2 mrad (4.3-8.5 with EKF2_TAU_VEL 0.03, three flights
    each). ``shows/sitl-px4.yaml``, 12 held-out, quiet, with EKF2_TAU_VEL 0.03: 8 and 5 of 12
    ``done`` in two runs, 6 without: within the spread of runs; kept as the sensor's own figure
    (issue 31, docs/sitl.md)."""
    per_sample = 0.01 + 0.13 * vibration
    return per_sample / math.sqrt(SIH_IMU_RATE_HZ / EKF2_STEP_HZ)


def px4_sih_degrees(value_deg: float) -> float:
    """The latitude or longitude in [deg] nearest ``value_deg`` that PX4 SIH can start at and
    whose truth is unbiased. SIH starts at its float32 SIH_LOC_LAT0/LON0 (PX4_HOME_LAT/LON);
    PX4 sends the true position (HIL_STATE_QUATERNION) as ``int32(lat * 1e7)``, cut towards
    zero (1.1 cm steps north, 0.9 cm east here), and the agent anchors the show frame on the
    first sample at rest. A flight's samples then average half a step short of the truth, the
    anchor short by where home lies in its step: together a fixed offset of up to half a step
    per axis, which the mocap the autopilot flies and the job metrics share (in PX4's ULogs of
    issue 31: 4-5 mm north on both vehicles, +1.6 and -2.0 mm east; predicted from the homes'
    place in their steps 5.2 and -2.4 mm). A home half-way along its step takes it out: of the
    float32 values within :data:`PX4_HOME_FLOAT32_STEPS` steps of ``value_deg``, the nearest
    whose ``abs(value * 1e7)`` lies within a tenth of a step of half-way (a bias of at most
    1.1 mm; at the show frame's origin the home moves by up to 3.5 m). A PX4 built by
    scripts/sitl/build.py also sends the truth as floats, which the agent then reads instead:
    this matters to PX4 as shipped."""
    half_way = math.copysign((math.floor(abs(value_deg) * 1e7) + 0.5) * 1e-7, value_deg)
    candidates = [_float32(half_way)]  # exact enough where float32 steps are finer than 1e-7
    here = struct.unpack("<i", struct.pack("<f", value_deg))[0]
    candidates += [struct.unpack("<f", struct.pack("<i", here + k))[0]
                   for k in range(-PX4_HOME_FLOAT32_STEPS, PX4_HOME_FLOAT32_STEPS + 1)]  # fmt: skip
    return min(
        candidates, key=lambda v: (abs((abs(v) * 1e7) % 1.0 - 0.5) > 0.1, abs(v - value_deg))
    )


def _float32(value: float) -> float:
    return float(struct.unpack("<f", struct.pack("<f", value))[0])

"""A simulator's true state of the vehicle, read off the autopilot's link (SITL only).

ArduPilot SITL sends its physics state as SIM_STATE (id 108; ``lat_int``/``lon_int`` in 1e-7
degrees, ``alt`` in metres, attitude in radians from NED); PX4 SITL (SIH) builds
HIL_STATE_QUATERNION (id 115; lat/lon in 1e-7 degrees, alt in millimetres) from its
ground-truth topics. :class:`TruthTracker` turns them into show-frame ENU positions: the first
sample taken while the vehicle rests disarmed at its home anchors the geodetic point to
``home_m_enu`` (the agent refuses a vehicle already armed at connect, so it is on its home then);
east and north follow on a local tangent plane (metres per 1e-7 degree: about 1.1 cm, which
bounds the resolution of the truth). A PX4 built by scripts/sitl/build.py also sends the same
truth's local position and velocity as floats (:data:`EXACT_TRUTH`, right after each
HIL_STATE_QUATERNION): once one comes, the positions are its, anchored the same way, and
HIL_STATE_QUATERNION gives only the attitude.

:func:`truth_mocap` makes a motion-capture source of it with the show's mocap latency and noise,
as a venue's mocap would be: the agent forwards that pose to the autopilot to fuse, while the job
metrics measure the truth itself.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Any

import numpy as np

from vehicle_agent.backends.base import Vec3
from vehicle_agent.backends.mavlink.frames import attitude_ned_to_enu, quaternion_to_euler
from vehicle_agent.backends.mavlink.mocap import MocapPose, MocapSource

EARTH_RADIUS_M = 6_378_137.0
TRUTH_MESSAGES: dict[str, int] = {"ardupilot": 108, "px4": 115}
"""The message id carrying the simulator's truth, per autopilot flavour."""
EXACT_TRUTH = "LOCAL_POSITION_NED_COV"
"""The message a PX4 built with scripts/sitl/source_edits.py sends beside each
HIL_STATE_QUATERNION: the same truth's local NED position [m] and velocity [m/s] as floats, its
``time_usec`` the same. PX4 sends this message nowhere else."""
TRUTH_KINDS = frozenset({"SIM_STATE", "HIL_STATE_QUATERNION", EXACT_TRUTH})
"""The messages :meth:`TruthTracker.absorb` takes."""


@dataclass(frozen=True)
class TruthSample:
    """The simulator's state of the vehicle at one instant."""

    time_s: float
    """Agent time in [s] when it arrived."""
    position_m_enu: Vec3
    """Vehicle reference point in [m], show frame ENU."""
    attitude_ned_rad: Vec3
    """Roll, pitch, yaw of the FRD body in NED, in [rad]."""


def geodetic(message: Any) -> tuple[float, float, float, Vec3] | None:
    """(lat [deg], lon [deg], alt [m], attitude NED [rad]) of a SIM_STATE or
    HIL_STATE_QUATERNION; None for any other message."""
    kind = message.get_type()
    if kind == "SIM_STATE":
        lat_e7 = getattr(message, "lat_int", 0) or message.lat
        lon_e7 = getattr(message, "lon_int", 0) or message.lon
        attitude = (float(message.roll), float(message.pitch), float(message.yaw))
        return lat_e7 * 1e-7, lon_e7 * 1e-7, float(message.alt), attitude
    if kind == "HIL_STATE_QUATERNION":
        q = tuple(float(x) for x in message.attitude_quaternion)
        attitude = quaternion_to_euler((q[0], q[1], q[2], q[3]))
        return message.lat * 1e-7, message.lon * 1e-7, message.alt * 1e-3, attitude
    return None


class TruthTracker:
    """The latest true states of one vehicle, in the show frame."""

    def __init__(self, home_m_enu: Vec3, history_s: float = 1.0) -> None:
        self.home_m_enu = home_m_enu
        self.history_s = history_s
        """How much history in [s] is kept (for the mocap latency)."""
        self.anchor: tuple[float, float, float] | None = None
        """Geodetic point (lat [deg], lon [deg], alt [m]) of ``home_m_enu``."""
        self.exact_anchor_m_ned: Vec3 | None = None
        """The simulator's local NED point in [m] of ``home_m_enu`` (None: no :data:`EXACT_TRUTH`
        placed yet; else every position is from that message)."""
        self._attitude_ned_rad: Vec3 | None = None
        """The latest truth's attitude, for the :data:`EXACT_TRUTH` that follows it."""
        self.samples: deque[TruthSample] = deque()

    @property
    def latest(self) -> TruthSample | None:
        return self.samples[-1] if self.samples else None

    def absorb(self, message: Any, now_s: float, *, resting_at_home: bool) -> bool:
        """Take one message in; True when it was a truth sample that could be placed."""
        if message.get_type() == EXACT_TRUTH:
            return self._absorb_exact(message, now_s, resting_at_home)
        fix = geodetic(message)
        if fix is None:
            return False
        lat, lon, alt, attitude = fix
        self._attitude_ned_rad = attitude
        if self.exact_anchor_m_ned is not None:
            return False  # its position to the float follows
        if self.anchor is None:
            if not resting_at_home:
                return False
            self.anchor = (lat, lon, alt)
        north, east = local_offset_m(self.anchor, lat, lon)
        self._place(now_s, north, east, alt - self.anchor[2], attitude)
        return True

    def _absorb_exact(self, message: Any, now_s: float, resting_at_home: bool) -> bool:
        attitude = self._attitude_ned_rad
        if attitude is None:
            return False
        ned = (float(message.x), float(message.y), float(message.z))
        anchor = self.exact_anchor_m_ned
        if anchor is None:
            if not resting_at_home:
                return False
            self.exact_anchor_m_ned = anchor = ned
            self.samples.clear()  # positions to the 1e-7 degree, anchored elsewhere
        self._place(now_s, ned[0] - anchor[0], ned[1] - anchor[1], anchor[2] - ned[2], attitude)
        return True

    def _place(self, now_s: float, north: float, east: float, up: float, attitude: Vec3) -> None:
        """Keep a sample ``north``/``east``/``up`` [m] of the home, and the last ``history_s``."""
        hx, hy, hz = self.home_m_enu
        self.samples.append(TruthSample(now_s, (hx + east, hy + north, hz + up), attitude))
        while self.samples and self.samples[0].time_s < now_s - self.history_s:
            self.samples.popleft()

    def at(self, time_s: float) -> TruthSample | None:
        """The newest sample no later than ``time_s`` [s] (None: none that old)."""
        for sample in reversed(self.samples):
            if sample.time_s <= time_s + 1e-9:
                return sample
        return None


def local_offset_m(
    anchor: tuple[float, float, float], lat_deg: float, lon_deg: float
) -> tuple[float, float]:
    """(north, east) in [m] of a point from ``anchor`` on the local tangent plane."""
    lat0, lon0, _ = anchor
    north = math.radians(lat_deg - lat0) * EARTH_RADIUS_M
    east = math.radians(lon_deg - lon0) * EARTH_RADIUS_M * math.cos(math.radians(lat0))
    return north, east


def truth_mocap(
    tracker: TruthTracker, latency_s: float, noise_std_m: float, seed: int
) -> MocapSource:
    """A mocap source from the truth: the state ``latency_s`` [s] old, with Gaussian noise of
    ``noise_std_m`` [m] per axis, stamped with the time it was captured."""
    rng = np.random.default_rng(seed)

    def pose(now_s: float) -> MocapPose | None:
        sample = tracker.at(now_s - latency_s)
        if sample is None:
            return None
        noise = rng.normal(0.0, noise_std_m, 3) if noise_std_m > 0 else np.zeros(3)
        p = sample.position_m_enu
        noisy = (p[0] + float(noise[0]), p[1] + float(noise[1]), p[2] + float(noise[2]))
        return MocapPose(noisy, attitude_ned_to_enu(*sample.attitude_ned_rad), sample.time_s)

    return pose

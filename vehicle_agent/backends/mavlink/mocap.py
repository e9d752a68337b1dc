"""Indoor flight: forward motion-capture poses to the autopilot as its position source.

With ``mocap: vision_position_estimate`` (ArduPilot with EK3_SRC1_POSXY = 6 ExternalNav, PX4 with
EKF2_EV_CTRL) or ``att_pos_mocap`` the backend sends the pose from ``mocap_source`` at
``mocap_rate_hz``, converted to the vehicle's LOCAL_NED frame; with ``odometry`` the pose and the
velocity between poses (:mod:`vehicle_agent.backends.mavlink.odometry`). The source is whatever
the venue's mocap client provides; it is asked for the pose at the agent's time.

The poses flow from a task of their own, not from the control loop's tick: the loop awaits the
autopilot's answers to mode changes and arming (seconds, with retries), and an estimator left
without its position source that long drops it. Measured on PX4 1.16 SIH: 4.8 s gaps while the
agent armed, EKF2 fell back to a fake position and refused arming ("Resolve system health
failures first") in 3 of 6 tries. :class:`TickTime` carries the agent's clock on between ticks.
"""

from __future__ import annotations

import asyncio
import logging
import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from vehicle_agent.backends.mavlink.frames import (
    LocalFrame,
    Vec3,
    attitude_enu_to_ned,
    euler_to_quaternion,
)
from vehicle_agent.backends.mavlink.odometry import PoseVelocity, encode_odometry
from vehicle_agent.backends.mavlink.params import Flavor

if TYPE_CHECKING:
    from vehicle_agent.backends.mavlink.link import MavlinkLink
    from vehicle_agent.backends.mavlink.settings import MavlinkSettings

log = logging.getLogger(__name__)

EKF_ORIGIN_LLA = (-35.363261, 149.165230, 584.0)
"""EKF origin (lat [deg], lon [deg], alt [m]) given to an autopilot flying on forwarded mocap:
its local frame is the mocap's whichever origin it has, but its EKF needs one. ArduPilot: the one
its GPS would set later while it fuses ExternalNav crashes ArduCopter 4.7 SITL (floating point
exception at "origin set", measured); set first, the GPS leaves it alone, but a GPS with a fix
can still come first (SITL under load: scripts/sitl/instances.py boots it without one, as
indoors). PX4 gets it at altitude
0 (see ``params.PX4_HGT_REF_VISION``)."""
PX4_ORIGIN_AFTER_POSES_S = 1.0
"""How long in [s] poses flow to PX4 before it gets its EKF origin. Given at connect, before the
first pose (a loaded machine: the simulator's truth came late), EKF2 took its height from the
barometer at the origin, 583.85 m, and never took the vision's 0 after it: the vehicle armed with
its local z at -583.85 m, climbed towards the ground and was disarmed by PX4's preflight timeout
(PX4 1.16 SIH, load 6, issue 31). With the vision fused first its local z is the mocap's."""


@dataclass(frozen=True)
class MocapPose:
    """One motion-capture frame of the vehicle, in the show frame."""

    position_m_enu: Vec3
    """Vehicle reference point in [m], ENU."""
    attitude_rad: Vec3 = (0.0, 0.0, 0.0)
    """Roll, pitch, yaw of the FLU body in ENU, in [rad]."""
    time_s: float | None = None
    """Capture time in [s] of the agent clock (None: now)."""


MocapSource = Callable[[float], MocapPose | None]
"""Agent time in [s] -> the latest pose, or None when the mocap has no frame."""


class TickTime:
    """The agent's time between its control ticks: the last tick's time carried on by the wall
    clock (``time.monotonic``) at the rate the recent ticks ran (the show's time scale)."""

    def __init__(self, window: int = 100) -> None:
        self._ticks: deque[tuple[float, float]] = deque(maxlen=window)  # (wall [s], agent [s])

    def ticked(self, agent_s: float, wall_s: float) -> None:
        """The control loop ticked at agent time ``agent_s`` [s], wall time ``wall_s`` [s]."""
        self._ticks.append((wall_s, agent_s))

    @property
    def rate(self) -> float:
        """Agent seconds per wall second over the recent ticks (1 until they span 0.05 s)."""
        if len(self._ticks) < 2:
            return 1.0
        (w0, a0), (w1, a1) = self._ticks[0], self._ticks[-1]
        return (a1 - a0) / (w1 - w0) if w1 - w0 >= 0.05 and a1 > a0 else 1.0

    def now_s(self, wall_s: float) -> float:
        """The agent time [s] at wall time ``wall_s`` [s] (0 before the first tick)."""
        if not self._ticks:
            return 0.0
        w1, a1 = self._ticks[-1]
        return a1 + max(0.0, wall_s - w1) * self.rate


class MocapForwarder:
    """Sends poses at a fixed rate (:meth:`run`) when the settings ask for it."""

    def __init__(
        self,
        settings: MavlinkSettings,
        frame: LocalFrame,
        source: MocapSource | None,
        flavor: Callable[[], Flavor],
    ):
        self.kind = settings.mocap
        self.flavor = flavor
        """The autopilot's flavour (known once its heartbeat came)."""
        self.velocity = PoseVelocity()
        self._task: asyncio.Task[None] | None = None
        self._origin_sent = False
        self._origin_for: int | None = None
        """System id whose EKF origin is asked for and not sent yet (PX4: until poses flowed)."""
        self.period_s = 1.0 / settings.mocap_rate_hz
        self.frame = frame
        self.source = source
        self.sent = 0
        self.failed = 0
        self.pose_at_s = -math.inf
        """Capture time in [s] (agent clock) of the latest pose sent."""
        self.first_pose_at_s = math.inf
        """Capture time in [s] (agent clock) of the first pose sent."""
        self.position_m_enu: Vec3 | None = None
        """Where the latest pose sent puts the vehicle, show frame ENU in [m]."""

    def start(self, link: Callable[[], MavlinkLink | None], clock: TickTime) -> None:
        """Forward from a task of its own (:meth:`run`) when the settings ask for mocap."""
        if self.kind != "none" and self._task is None:
            self._task = asyncio.create_task(self.run(link, clock))

    def stop(self) -> None:
        if self._task is not None:
            self._task.cancel()
            self._task = None

    def age_s(self, now_s: float) -> float | None:
        """Age in [s] at agent time ``now_s`` of the latest pose sent (infinite: none yet);
        None when no mocap is forwarded."""
        return None if self.kind == "none" else now_s - self.pose_at_s

    @property
    def origin_sent(self) -> bool:
        """The autopilot's EKF has been given its origin (:meth:`set_ekf_origin`)."""
        return self._origin_sent

    def set_ekf_origin(self, link: MavlinkLink, system_id: int) -> None:
        """An autopilot fusing our mocap: give its EKF an origin (once), before its GPS does;
        PX4's once poses have flowed for :data:`PX4_ORIGIN_AFTER_POSES_S` (then sent by
        :meth:`forward`)."""
        if self._origin_sent or self.kind == "none":
            return
        self._origin_for = system_id
        flowed_s = self.pose_at_s - self.first_pose_at_s  # -inf before the first pose
        if self.flavor() == "px4" and not flowed_s >= PX4_ORIGIN_AFTER_POSES_S:
            return
        self._origin_sent = True
        lat, lon, alt = EKF_ORIGIN_LLA
        if self.flavor() == "px4":
            alt = 0.0
        link.send(link.mav.set_gps_global_origin_encode(
            system_id, round(lat * 1e7), round(lon * 1e7), round(alt * 1000)))  # fmt: skip
        log.info("vehicle %s: EKF origin set for mocap flight", system_id)

    async def run(self, link: Callable[[], MavlinkLink | None], clock: TickTime) -> None:
        """Forward poses at the rate until cancelled, whatever the control loop awaits;
        ``link`` gives the open link (None: closed, nothing sent)."""
        due_s = time.monotonic()  # wall clock, paced on deadlines so that late wake-ups even out
        while True:
            current = link()
            try:
                if current is not None:
                    self.forward(current, clock.now_s(time.monotonic()))
            except Exception:  # a bad pose must not end the estimator's position source
                self.failed += 1
                if self.failed in (1, 10) or self.failed % 1000 == 0:
                    log.exception("mocap pose not forwarded (%d so far)", self.failed)
            due_s = max(due_s + self.period_s / max(clock.rate, 1e-3), time.monotonic() - 0.1)
            await asyncio.sleep(max(0.0, due_s - time.monotonic()))

    def forward(self, link: MavlinkLink, now_s: float) -> None:
        """Send the pose at agent time ``now_s`` [s], if the source has one."""
        if self.kind == "none" or self.source is None:
            return
        pose = self.source(now_s)
        if pose is None:
            return
        x, y, z = self.frame.position_to_ned(pose.position_m_enu)
        roll, pitch, yaw = attitude_enu_to_ned(*pose.attitude_rad)
        usec = int((pose.time_s if pose.time_s is not None else now_s) * 1e6)
        if self.kind == "odometry":
            velocity = self.velocity.update(usec * 1e-6, (x, y, z))
            message = encode_odometry(link.mav, self.flavor(), usec, (x, y, z), (roll, pitch, yaw),
                                      velocity)  # fmt: skip
        elif self.kind == "vision_position_estimate":
            message = link.mav.vision_position_estimate_encode(usec, x, y, z, roll, pitch, yaw)
        else:
            q = euler_to_quaternion(roll, pitch, yaw)
            message = link.mav.att_pos_mocap_encode(usec, q, x, y, z)
        if link.send(message):
            self.sent += 1
            self.pose_at_s = usec * 1e-6
            self.first_pose_at_s = min(self.first_pose_at_s, self.pose_at_s)
            self.position_m_enu = pose.position_m_enu
            if self._origin_for is not None:
                self.set_ekf_origin(link, self._origin_for)

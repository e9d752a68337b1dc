"""What the MAVLink backend measures for the agent's preflight (pure): messages lost on the link,
from their sequence numbers; the estimator's flags in words; the autopilot's fence read back.

Every MAVLink message carries an 8-bit sequence number its sender counts per component
(mavlink.io, "Packet Serialization": ``seq``, used to detect packet loss): a gap of ``k`` between
consecutive messages of one component is ``k`` messages lost. A jump of half the range or more
is taken as the sender restarting (or messages reordered), not as loss.
"""

from __future__ import annotations

from collections import deque
from typing import Any

from vehicle_agent.backends.base import LinkHealth
from vehicle_agent.backends.mavlink.state import LinkState

SEQ_RANGE = 256
LOSS_WINDOW = 500
"""Messages (received and lost) the loss is counted over: 2-5 s of an autopilot's telemetry."""
LOSS_MIN_COUNT = 50
"""Fewer messages than this in the window say nothing yet (None)."""

ESTIMATOR_NEEDS = (
    (1, "no attitude"),
    (2, "no horizontal velocity"),
    (4, "no vertical velocity"),
    (8, "no horizontal position"),
    (32, "no vertical position"),
)
"""Bits of ESTIMATOR_STATUS / EKF_STATUS_REPORT ``flags`` a writing vehicle needs (the first
five bits mean the same in both: MAV ESTIMATOR_STATUS_FLAGS and ArduPilot's EKF_STATUS_FLAGS).
Not CONST_POS_MODE (128): PX4 sets it whenever the vehicle is at rest, whatever it fuses
(ekf_helper.cpp: ``fake_pos || valid_fake_pos || vehicle_at_rest``), and held every PX4 SITL
vehicle on the ground; an estimator with no position source lacks bit 8 anyway."""
ESTIMATOR_MESSAGE = {"ardupilot": 193, "px4": 230}
"""The message each autopilot reports those flags in, asked for at 1 Hz at connect with the
other slow messages (``connect.request_telemetry``): ArduPilot's EKF_STATUS_REPORT (193),
PX4's ESTIMATOR_STATUS (230). PX4 streams ESTIMATOR_STATUS by itself only in some link modes
(0.5 Hz on a normal link: mavlink_main.cpp), and a link that never sends it leaves the estimator
check with nothing to say."""
FENCE_READ_BACK = {"ardupilot": "FENCE_ENABLE", "px4": "GF_ACTION"}
"""The fence parameter each autopilot must have read back at connect, when one was asked."""


class SequenceLoss:
    """Messages lost per sending component, over the last :data:`LOSS_WINDOW` (pure)."""

    def __init__(self, window: int = LOSS_WINDOW) -> None:
        self._last_seq: dict[tuple[int, int], int] = {}
        self._window: deque[int] = deque(maxlen=window)
        """Per message received: how many were lost just before it."""

    def saw(self, system_id: int, component_id: int, seq: int) -> None:
        """A message of ``(system_id, component_id)`` with sequence number ``seq`` arrived."""
        key = (system_id, component_id)
        last = self._last_seq.get(key)
        self._last_seq[key] = seq
        if last is None:
            return
        gap = (seq - last - 1) % SEQ_RANGE
        self._window.append(gap if gap < SEQ_RANGE // 2 else 0)

    @property
    def fraction(self) -> float | None:
        """Share of the messages of the window lost, 0..1 (None: too few to say)."""
        received = len(self._window)
        if received < LOSS_MIN_COUNT:
            return None
        lost = sum(self._window)
        return lost / (lost + received)


def estimator_problem(flags: int | None) -> str | None:
    """What the estimator lacks, from its status ``flags`` (None: healthy, or never sent)."""
    if flags is None:
        return None
    missing = [words for bit, words in ESTIMATOR_NEEDS if not flags & bit]
    return ", ".join(missing) or None


def fence_problem(
    fence_asked: bool, set_params: bool, params_set: dict[str, float], flavor: str
) -> str | None:
    """Why the autopilot's own fence is not in place: one was asked (the vehicle's settings:
    ``fence`` given, ``set_params``) and not read back (``params_set``)."""
    if not fence_asked:
        return None
    if not set_params:
        return "the autopilot's fence is asked but set_params is off"
    name = FENCE_READ_BACK.get(flavor)
    if name is not None and name not in params_set:
        return f"the autopilot's fence ({name}) was not read back at connect"
    return None


def link_health(
    state: LinkState,
    losses: SequenceLoss | None,
    heartbeat_age_s: float,
    mocap_age_s: float | None,
    fence: str | None,
) -> LinkHealth:
    """The figures of the preflight, from what the backend has measured."""
    return LinkHealth(
        link_age_s=None if heartbeat_age_s != heartbeat_age_s else heartbeat_age_s,  # NaN
        link_loss_fraction=None if losses is None else losses.fraction,
        estimator=estimator_problem(state.estimator_flags),
        mocap_age_s=mocap_age_s,
        fence=fence,
    )


def seq_of(message: Any) -> tuple[int, int, int]:
    """(system, component, seq) of a decoded pymavlink message."""
    return message.get_srcSystem(), message.get_srcComponent(), message.get_seq()

"""The agent's heartbeat schedule (issue 15): a status at least every second, and something of
its own at least every ``lost_after_s / 3``; a vehicle at rest sends two messages a second."""

from __future__ import annotations

import itertools
import math

import pytest

from vehicle_agent.heartbeat import HEARTBEAT_SLACK_S, status_due_s

LOST_AFTER_S = 1.5
STATUS_PERIOD_S = 1.0
REST_TELEMETRY_S = 1.0  # vehicle_agent.rest.REST_PERIOD_S: a resting vehicle's telemetry period


def _rest(
    duration_s: float, *, status_first: bool, step_s: float = 0.001
) -> tuple[list[float], list[float]]:
    """Times of the statuses and of all messages of a vehicle at rest, on a fine clock; the
    heartbeat sends a status ``HEARTBEAT_SLACK_S`` early, and when both are due at one instant
    the status or the telemetry goes first (``status_first``): the agent's tasks race."""
    status_at = spoke_at = -math.inf
    statuses, spoken = [], []
    next_telemetry_s = 0.25

    def heartbeat(now_s: float) -> None:
        nonlocal status_at, spoke_at
        due_s = status_due_s(status_at, spoke_at, STATUS_PERIOD_S, LOST_AFTER_S)
        if now_s >= due_s - HEARTBEAT_SLACK_S:
            status_at = spoke_at = now_s
            statuses.append(now_s)
            spoken.append(now_s)

    for k in range(int(duration_s / step_s)):
        now_s = k * step_s
        if status_first:
            heartbeat(now_s)
        if now_s >= next_telemetry_s:
            next_telemetry_s += REST_TELEMETRY_S
            spoke_at = now_s
            spoken.append(now_s)
        if not status_first:
            heartbeat(now_s)
    return statuses, spoken


@pytest.mark.parametrize("status_first", [False, True])
def test_a_vehicle_at_rest_sends_its_status_at_1_hz_between_its_telemetry(
    status_first: bool,
) -> None:
    statuses, spoken = _rest(20.0, status_first=status_first)
    assert 19 <= len(statuses) <= 21  # 1 Hz (before: every lost_after_s / 4, 2.7 Hz)
    assert 39 <= len(spoken) <= 42  # with the 1 Hz telemetry: two messages a second
    gaps = [b - a for a, b in itertools.pairwise(spoken)]
    assert max(gaps) <= 1.1 * LOST_AFTER_S / 3 + 0.01  # heard well within lost_after_s


def test_a_flying_vehicle_sends_its_status_every_second_and_a_silent_one_sooner() -> None:
    telemetry_just_now = status_due_s(10.0, 10.9, STATUS_PERIOD_S, LOST_AFTER_S)
    assert telemetry_just_now == 11.0  # its 20 Hz telemetry keeps it heard
    silent = status_due_s(10.0, 10.0, STATUS_PERIOD_S, LOST_AFTER_S)
    assert silent == pytest.approx(10.0 + 1.1 * LOST_AFTER_S / 3)
    assert status_due_s(-math.inf, -math.inf, STATUS_PERIOD_S, LOST_AFTER_S) == -math.inf

"""``skyquill down``'s first step: land every vehicle in the air, over the bus, before any process
of the show stops.

As the show's ``operator`` identity (``trust/acl.py``: operator commands, and ``land`` straight to
a vehicle's ``command`` key), it listens to the vehicles' statuses (each at least every second,
``ServiceSettings.status_period_s``) to learn which are in the air, then, when any is:

- the orchestrator answers: ``land_all`` (one host of a show across machines: ``land`` of each
  of its vehicles), the operator's own command, so the orchestrator does what it does for it
  (``orchestrator/operator.py``): each job being written goes back to the queue, its board
  half-written waits for a fresh sheet, the vehicles are held and, for ``land_all``, the queue
  paused, all in its durable store and event log;
- it does not: ``land`` straight to each vehicle in the air; its agent abandons the job, which
  the orchestrator takes back when it runs again (the vehicle's new start names no job,
  ``orchestrator/presence.py``).

Then it waits until each of them says it is on the ground, up to a bound, one line per vehicle.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from bus.keys import ShowKeys
from bus.messages import (
    AIRBORNE_STATES,
    CommandReply,
    OperatorCommand,
    VehicleCommand,
    VehicleStatus,
)
from bus.pubsub import subscribe
from bus.rpc import NoReplyError, RemoteError, query_one
from bus.session import Session, SessionOpenError, open_session
from showfile import Show
from trust.settings import session_settings

HEAR_S = 1.5
"""How long to listen for the vehicles' statuses before deciding which fly, wall [s]: each
agent publishes its status at least every second (``ServiceSettings.status_period_s``)."""
OPEN_TIMEOUT_S = 2.0
"""How long to try to reach the show's router, wall [s]."""
ANSWER_TIMEOUT_S = 3.0
"""How long the orchestrator or an agent has to answer a command, wall [s]."""
WATCH_PERIOD_S = 0.1
"""How often the wait looks at the statuses, wall [s]."""
OPERATOR = "skyquill down"
"""Who the event log says landed the vehicles."""


@dataclass(frozen=True)
class Landed:
    """How the landing went."""

    flying: list[str]
    """The vehicles that were in the air."""
    not_down: list[str]
    """Those that did not say they were down in time."""
    held: bool
    """Whether the orchestrator landed them (its hold and, for ``land_all``, its pause of the
    queue outlive the show's stop: ``release`` / ``release-all`` and ``resume`` undo them)."""


@dataclass(frozen=True)
class Heard:
    """A vehicle's latest status, as far as landing goes."""

    state: str
    """Its ``VehicleStatus.state``."""
    message: str
    """Its status message."""


class Statuses:
    """The latest status of each vehicle, as Zenoh's threads deliver them."""

    def __init__(self, vehicle_ids: Sequence[str]) -> None:
        self._wanted = set(vehicle_ids)
        self._lock = threading.Lock()
        self._latest: dict[str, Heard] = {}

    def heard(self, vehicle_id: str, heard: Heard) -> None:
        if vehicle_id in self._wanted:
            with self._lock:
                self._latest[vehicle_id] = heard

    def latest(self) -> dict[str, Heard]:
        with self._lock:
            return dict(self._latest)

    def all_heard(self) -> bool:
        with self._lock:
            return self._latest.keys() >= self._wanted


def in_the_air(latest: dict[str, Heard]) -> list[str]:
    """The vehicles whose latest status says they fly (or move, a ground vehicle), sorted."""
    return sorted(vid for vid, heard in latest.items() if heard.state in AIRBORNE_STATES)


def land_before_stop(
    show: Show,
    vehicle_ids: Sequence[str],
    *,
    whole_show: bool,
    timeout_s: float,
    say: Callable[[str], None],
) -> Landed:
    """Land the vehicles of ``vehicle_ids`` that are in the air and wait up to ``timeout_s`` wall
    [s] for each to say it is down. ``whole_show``: every vehicle of the show is here
    (``land_all``)."""
    try:
        session = open_session(
            session_settings(show, "operator"), role="client", open_timeout_s=OPEN_TIMEOUT_S
        )
    except SessionOpenError as exc:
        say(
            f"cannot reach the show's bus ({exc}); no vehicle told to land: each agent lands "
            "its vehicle before it stops"
        )
        return Landed([], [], held=False)
    with session:
        keys = ShowKeys(show.show_id)
        statuses = Statuses(vehicle_ids)
        subscribe(
            session,
            keys.vehicle_status_all,
            VehicleStatus,
            lambda _key, st: statuses.heard(st.vehicle_id, Heard(st.state, st.message)),
        )
        deadline = time.monotonic() + HEAR_S
        while not statuses.all_heard() and time.monotonic() < deadline:
            time.sleep(WATCH_PERIOD_S)
        flying = in_the_air(statuses.latest())
        if not flying:
            say("no vehicle in the air")
            return Landed([], [], held=False)
        say(f"{_names(flying)} {'is' if len(flying) == 1 else 'are'} in the air: landing first")
        held = _order_landing(session, keys, flying, whole_show, say)
        return Landed(flying, _wait_landed(statuses, flying, timeout_s, say), held)


def _order_landing(
    session: Session,
    keys: ShowKeys,
    flying: list[str],
    whole_show: bool,
    say: Callable[[str], None],
) -> bool:
    """Through the orchestrator when it answers (True), else straight to each vehicle."""
    orders = (
        [OperatorCommand(command="land_all", operator=OPERATOR, reason=OPERATOR)]
        if whole_show
        else [
            OperatorCommand(command="land", vehicle_id=vid, operator=OPERATOR, reason=OPERATOR)
            for vid in flying
        ]
    )
    try:
        replies = [
            query_one(session, keys.command, order, CommandReply, timeout_s=ANSWER_TIMEOUT_S)
            for order in orders
        ]
    except (NoReplyError, RemoteError) as exc:
        say(f"the orchestrator does not answer ({exc}); telling each vehicle to land")
    else:
        refused = [reply.message for reply in replies if not reply.ok]
        if not refused:
            jobs = "its job goes" if len(flying) == 1 else "their jobs go"
            say(f"the orchestrator lands {_names(flying)}: {jobs} back to the queue")
            return True
        say(f"the orchestrator refused ({'; '.join(refused)}); telling each vehicle to land")
    for vid in flying:
        try:
            reply = query_one(
                session,
                keys.vehicle_command(vid),
                VehicleCommand(command="land"),
                CommandReply,
                timeout_s=ANSWER_TIMEOUT_S,
            )
            say(f"{vid}: {reply.message}")
        except (NoReplyError, RemoteError) as exc:
            say(f"{vid} did not take the land command ({exc})")
    return False


def _wait_landed(
    statuses: Statuses, flying: list[str], timeout_s: float, say: Callable[[str], None]
) -> list[str]:
    """Wait until each of ``flying`` says it is down; returns those that did not in time."""
    started = time.monotonic()
    waiting = set(flying)
    while waiting and time.monotonic() - started < timeout_s:
        latest = statuses.latest()
        for vid in sorted(waiting):
            if latest[vid].state not in AIRBORNE_STATES:
                say(f"{vid} {latest[vid].state} after {time.monotonic() - started:.1f} s")
                waiting.discard(vid)
        time.sleep(WATCH_PERIOD_S)
    latest = statuses.latest()
    for vid in sorted(waiting):
        heard = latest[vid]
        say(
            f"{vid} has not said it landed in {timeout_s:.0f} s (last: {heard.state}"
            f"{': ' + heard.message if heard.message else ''})"
        )
    return sorted(waiting)


def _names(vehicle_ids: Sequence[str]) -> str:
    return ", ".join(vehicle_ids)

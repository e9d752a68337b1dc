"""The vehicles' clocks against the orchestrator's: its side of the measurement, and the alert.

Each agent measures its machine's wall clock against the orchestrator's, as NTP does, on the
``orchestrator/clock`` queryable (``vehicle_agent/clock_sync.py`` explains the exchange), holds
its vehicle by its preflight past the show's ``preflight.clock_offset_max_s``, and reports the
offset in its status (``clock_offset_ms``). The orchestrator answers the queryable with its own
wall clock (:func:`clock_reply`, on Zenoh's thread, so that no wait in its event loop lies
between the query's arrival and its stamps) and raises one alert (``clock_offset``) when a
vehicle's reported offset passes the bound, open until a status reports it within the bound
again (then an ``info`` event says so). A status that reports no offset (an agent just started,
not measured yet) changes nothing: a restarted agent with the same clock raises no second alert.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from bus.messages import ClockReply
from orchestrator.core_types import Effects
from orchestrator.fleet import VehicleView

if TYPE_CHECKING:
    from orchestrator.book_protocol import BookProtocol


def clock_reply(wall_clock: Callable[[], float]) -> ClockReply:
    """The reply to a clock query: the orchestrator's wall clock (Unix time in [s]) when the
    query came and when it is answered (NTP's receive and transmit timestamps)."""
    receive_s = wall_clock()
    return ClockReply(receive_s=receive_s, transmit_s=wall_clock())


def heard(
    book: BookProtocol, eff: Effects, view: VehicleView, offset_ms: float | None, now_s: float
) -> None:
    """A status's ``clock_offset_ms``: the alert when it passes the bound, the all-clear when
    it comes back within it."""
    if offset_ms is None:
        return
    bound_ms = 1e3 * book.config.clock_offset_max_s
    off = abs(offset_ms) > bound_ms
    if off == view.clock_off:
        return
    view.clock_off = off
    vid = view.info.vehicle_id
    if off:
        message = (
            f"{vid} clock {offset_ms:+.0f} ms off the orchestrator's (limit {bound_ms:.0f} ms): "
            "held by its preflight; synchronise its clock (NTP/PTP)"
        )
        book.event(eff, now_s, "alert", "clock_offset", message, vehicle_id=vid)
    else:
        message = (
            f"{vid} clock within {bound_ms:.0f} ms of the orchestrator's ({offset_ms:+.0f} ms)"
        )
        book.event(eff, now_s, "info", "clock_offset", message, vehicle_id=vid)

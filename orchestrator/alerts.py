"""Open alerts (pure): the show's alerts whose cause lasts, kept until it is gone.

A console that was not connected when an alert was raised must still see it while it matters.
An alert is *open* while the state it reported holds; each cause keeps its newest alert:

==================  ===================================  ===================================
alert (kind)        cause                                closes when
==================  ===================================  ===================================
``vehicle_held``    the vehicle is held (fault, lost in  ``release`` / ``release_all``
                    the air and back without its job)
``operator``        ``estop`` of one vehicle: it is      ``release`` of it; of all: every
(``estop``)         held; of all: every vehicle is       vehicle released
``vehicle_lost``    the vehicle is lost                  it is heard again
``vehicle_fault``   its agent reported a backend fault   a later status not in ``fault``
``board_dirty``     the board is half-written            ``fresh_sheet``
``job_waits``       a job waits past its hold for its    its vehicle heard again, or
                    lost vehicle (``holders.py``)        ``fresh_sheet`` of its board
``disk_full``       the orchestrator writes on its disk  ``disk_room``: room made again (not
                    reserve (``orchestrator/disk_room``)  kept over a restart: the new process
                                                         checks its disk and says it again)
``clock_offset``    its agent reported its clock past    a status reporting it within the
                    ``preflight.clock_offset_max_s``     bound (``clock_offsets.py``)
==================  ===================================  ===================================

Other alerts (``limit``, ``job_failed``, safety aborts, autopilot messages) tell of a moment, not
of a lasting state: they are in the event log only. After an orchestrator restart the open
alerts come back from the database (``orchestrator/store.py``) and stay open until their
vehicle says otherwise: a vehicle not heard since is still lost, and its fault still stands.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from bus.messages import Event
from orchestrator.fleet import VehicleView

EVERY_VEHICLE = "*"
"""The vehicle of a cause that concerns the whole fleet (an ``estop`` of all)."""
DISK_CAUSE = ("disk", "show")
"""The cause of ``disk_full``: the show's disk, until a ``disk_room`` event."""


def cause_of(event: Event, vehicles: Mapping[str, VehicleView]) -> tuple[str, str] | None:
    """The lasting cause an alert reports, as (what, vehicle or board id); None: none lasts."""
    vid = event.vehicle_id
    if event.level != "alert":
        return None
    if event.kind == "operator":  # the only operator alert is estop's
        return ("held", vid or EVERY_VEHICLE)
    if event.kind == "disk_full":
        return DISK_CAUSE
    view = vehicles.get(vid) if vid is not None else None
    if view is None:
        return None
    if event.kind in ("board_dirty", "job_waits"):  # both until a fresh sheet
        return ("dirty", view.info.board_id)
    what = {
        "vehicle_held": "held",
        "vehicle_lost": "lost",
        "vehicle_fault": "fault",
        "clock_offset": "clock",
    }
    return (what[event.kind], view.info.vehicle_id) if event.kind in what else None


class OpenAlerts:
    """The newest alert of each lasting cause, until that cause is gone."""

    def __init__(self, alerts: Iterable[Event], vehicles: Mapping[str, VehicleView]) -> None:
        """``alerts``: those open when the orchestrator stopped (as stored)."""
        self._open: dict[tuple[str, str], Event] = {}
        for event in alerts:
            if cause_of(event, vehicles) != DISK_CAUSE:
                self.saw(event, vehicles)

    def saw(self, event: Event, vehicles: Mapping[str, VehicleView]) -> bool:
        """Keep ``event`` if it is an alert of a lasting cause (or close the disk's on
        ``disk_room``); whether the open alerts changed."""
        if event.kind == "disk_room":
            return self._open.pop(DISK_CAUSE, None) is not None
        cause = cause_of(event, vehicles)
        if cause is not None:
            self._open[cause] = event
        return cause is not None

    def current(self, vehicles: Mapping[str, VehicleView], dirty_boards: set[str]) -> list[Event]:
        """The alerts still open, oldest first (those whose cause is gone are dropped)."""
        for cause, event in list(self._open.items()):
            if not _lasts(cause, event, vehicles, dirty_boards):
                del self._open[cause]
        return sorted(self._open.values(), key=lambda e: e.time_s)


def _lasts(
    cause: tuple[str, str],
    event: Event,
    vehicles: Mapping[str, VehicleView],
    dirty_boards: set[str],
) -> bool:
    what, name = cause
    if cause == DISK_CAUSE:
        return True  # until ``disk_room``
    if what == "dirty":
        return name in dirty_boards
    if name == EVERY_VEHICLE:
        return any(view.held for view in vehicles.values())
    view = vehicles.get(name)
    if view is None:
        return False
    if what == "held":
        return view.held
    if what == "lost":
        return view.lost
    if what == "clock":
        return view.clock_off
    heard_after = view.status_at_s is not None and view.status_at_s > event.time_s
    return not (heard_after and view.state != "fault")

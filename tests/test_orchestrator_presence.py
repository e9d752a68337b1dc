"""Presence (pure): a vehicle is present while its token is there *and* it speaks (heartbeat)."""

from __future__ import annotations

from bus.messages import AgentReport, OperatorCommand, SubmitRequest, VehicleStatus
from orchestrator.core import Book, CoreConfig, Effects
from orchestrator.fleet import VehicleInfo

VEHICLES = (
    VehicleInfo("uav1", "quadrotor-brush", "b1"),
    VehicleInfo("uav2", "quadrotor-brush", "b2"),
)
LOST_AFTER_S = 1.5
HEARTBEAT_S = LOST_AFTER_S / 4


def _book() -> Book:
    return Book(CoreConfig(show_id="t", vehicles=VEHICLES, lost_after_s=LOST_AFTER_S), now_s=0.0)


def _status(vid: str, job_id: str | None = None, state: str = "idle") -> VehicleStatus:
    return VehicleStatus(vehicle_id=vid, kind="q", state=state, job_id=job_id, incarnation="a")  # type: ignore[arg-type]


def _run(book: Book, start_s: float, end_s: float, speaking: dict[str, str | None]) -> Effects:
    """Timer ticks every 0.1 s from ``start_s`` to ``end_s``; the vehicles in ``speaking``
    send a status every heartbeat (with that job); all effects merged."""
    merged = Effects()
    now, next_beat = start_s, start_s
    while now < end_s - 1e-9:
        now = round(now + 0.1, 6)
        effects = [book.tick(now)]
        if now >= next_beat:
            next_beat += HEARTBEAT_S
            for vid, job in speaking.items():
                state = "writing" if job else "idle"
                effects.append(book.status(_status(vid, job, state), now))
        for eff in effects:
            merged.jobs.update(eff.jobs)
            merged.events += eff.events
            merged.commands += eff.commands
    return merged


def _online(book: Book, vid: str, now_s: float) -> None:
    book.liveliness(vid, True, now_s)
    book.status(_status(vid), now_s)


def _writing_j1(book: Book) -> None:
    _online(book, "uav1", 0.0)
    reply, _ = book.submit("j1", SubmitRequest(text="L"), label="L", estimate_s=9.0, now_s=0.1)
    assert reply.ok and book.jobs["j1"].vehicle_id == "uav1"
    book.report(AgentReport(vehicle_id="uav1", job_id="j1", event="started"), 0.2)


def test_a_silent_vehicle_is_lost_although_its_token_remains_and_back_when_it_speaks() -> None:
    book = _book()
    _writing_j1(book)
    _run(book, 0.2, 2.0, {"uav1": "j1"})
    assert book.jobs["j1"].state == "writing"
    eff = _run(book, 2.0, 4.0, {})  # frozen: its token stays, its heartbeat stops
    lost = [e for e in eff.events if e.kind == "vehicle_lost"]
    assert len(lost) == 1 and "silent for 1.5 s although its token remains" in lost[0].message
    assert lost[0].time_s - 2.0 <= HEARTBEAT_S + LOST_AFTER_S  # silent since its last beat
    assert book.vehicles["uav1"].alive and book.vehicles["uav1"].lost
    requeued = book.jobs["j1"]
    assert requeued.state == "queued" and requeued.error is not None
    assert requeued.error.code == "vehicle_lost"
    assert book.dirty_boards == set()  # it may be writing on, unheard
    eff = book.status(_status("uav1"), 4.1)  # it speaks again (without the job: it gave it up)
    kinds = ["vehicle_appeared", "board_dirty", "job_released", "vehicle_held"]
    assert [e.kind for e in eff.events] == kinds  # lost in the air: held until released
    assert book.dirty_boards == {"b1"}
    assert not book.vehicles["uav1"].lost


def test_a_token_alone_never_makes_a_vehicle_present() -> None:
    book = _book()
    book.liveliness("uav2", True, 0.0)  # anyone could declare it; no status ever comes
    reply, eff = book.submit("j1", SubmitRequest(text="L"), label="L", estimate_s=9.0, now_s=0.1)
    assert reply.ok and eff.commands == []
    eff = _run(book, 0.1, 3.0, {})
    assert eff.commands == [] and book.vehicles["uav2"].lost
    assert book.snapshot(3.0).vehicles[1].state == "lost"


def test_an_orchestrator_that_stalled_waits_for_the_heartbeats_that_queued_up() -> None:
    book = _book()
    _writing_j1(book)
    _run(book, 0.2, 1.0, {"uav1": "j1"})
    assert book.tick(3.0).events == []  # 2 s without looking: not the vehicle's silence
    assert not book.vehicles["uav1"].lost
    book.status(_status("uav1", "j1", "writing"), 3.05)  # the queued heartbeats arrive
    _run(book, 3.0, 5.0, {"uav1": "j1"})
    assert book.jobs["j1"].state == "writing"


def test_a_vehicle_back_with_the_job_it_had_gets_it_back_unless_another_has_it() -> None:
    book = _book()
    _writing_j1(book)
    book.liveliness("uav1", False, 1.0)  # e.g. the router restarted
    _run(book, 1.0, 2.6, {})
    queued = book.jobs["j1"]
    assert queued.state == "queued" and book.vehicles["uav1"].lost
    book.liveliness("uav1", True, 2.7)
    eff = book.status(_status("uav1", "j1", "returning"), 2.7)  # written; report on its way
    assert [e.kind for e in eff.events] == ["vehicle_appeared", "job_reclaimed"]
    reclaimed = book.jobs["j1"]
    assert reclaimed.state == "assigned" and reclaimed.vehicle_id == "uav1"
    done = AgentReport(vehicle_id="uav1", job_id="j1", event="done", progress=1.0)
    assert book.report(done, 2.8)[0].ok
    assert book.jobs["j1"].state == "done"


def test_someone_elses_queued_job_is_never_taken_by_naming_it() -> None:
    book = _book()
    _writing_j1(book)
    _online(book, "uav2", 0.3)
    book.operator(OperatorCommand(command="pause", vehicle_id="uav2"), 0.3)  # j1 stays queued
    book.liveliness("uav1", False, 1.0)
    _run(book, 1.0, 2.6, {"uav2": None})
    assert book.jobs["j1"].state == "queued"
    eff = book.status(_status("uav2", "j1", "writing"), 2.7)  # uav2 claims it: it never had it
    assert [e.kind for e in eff.events if e.kind == "job_reclaimed"] == []
    assert book.jobs["j1"].state == "queued" and book.jobs["j1"].vehicle_id == "uav1"


def test_clear_fault_is_forwarded_to_the_vehicle_and_keeps_the_hold() -> None:
    book = _book()
    _online(book, "uav1", 0.0)
    book.operator(OperatorCommand(command="estop", vehicle_id="uav1"), 1.0)
    missing, _ = book.operator(OperatorCommand(command="clear_fault"), 2.0)
    assert missing.error is not None and missing.error.field == "vehicle_id"
    reply, eff = book.operator(OperatorCommand(command="clear_fault", vehicle_id="uav1"), 2.0)
    assert reply.ok and [(v, c.command) for v, c in eff.commands] == [("uav1", "clear_fault")]
    assert book.vehicles["uav1"].held  # release is still the operator's decision


def test_an_agent_restarted_without_its_job_gives_it_back_at_once_a_token_flap_does_not() -> None:
    book = _book()
    _writing_j1(book)
    _run(book, 0.2, 1.0, {"uav1": "j1"})
    book.liveliness("uav1", False, 1.05)  # a network flap: the same agent, still writing j1
    book.liveliness("uav1", True, 1.1)
    _run(book, 1.1, 5.0, {"uav1": "j1"})
    assert book.jobs["j1"].state == "writing"
    book.liveliness("uav1", False, 5.05)  # killed, and restarted by its supervisor at once
    book.liveliness("uav1", True, 5.3)
    reborn = VehicleStatus(vehicle_id="uav1", kind="q", state="idle", incarnation="new")
    eff = book.status(reborn, 5.35)  # its new self has no job
    assert eff.jobs["j1"].state in ("queued", "assigned") and eff.jobs["j1"].vehicle_id == "uav1"
    assert [e.message for e in eff.events if e.kind == "job_requeued"] == [
        "L: uav1 restarted without it"
    ]


def test_tokens_flapping_with_the_orchestrators_reconnection_are_no_restart() -> None:
    """The orchestrator frozen past its session's lease (or the router restarted) sees every
    token go and come back; the agent, unacknowledged meanwhile, gave its job up. Its job is a
    hand-back after the grace (no attempt counted), not a restart."""
    book = _book()
    _writing_j1(book)
    same = VehicleStatus(vehicle_id="uav1", kind="q", state="writing", job_id="j1", incarnation="a")
    book.status(same, 0.3)
    book.liveliness("uav1", False, 2.0)
    book.liveliness("uav1", True, 2.0)
    gave_up = VehicleStatus(vehicle_id="uav1", kind="q", state="returning", incarnation="a")
    assert not book.status(gave_up, 2.1).jobs
    book.status(gave_up, 2.2 + book.config.confirm_grace_s)
    job = book.jobs["j1"]
    assert (job.state, job.attempts, job.handbacks) == ("queued", 1, 1)


def test_an_agent_restarted_unseen_by_liveliness_is_known_by_its_new_incarnation() -> None:
    """A restart whose token the orchestrator never saw go (the new token came first, or the
    router merged them) is told by the status's ``incarnation``: the job is taken back at once and
    counts as an attempt; the same agent not naming its job is a hand-back after the grace."""
    book = _book()
    _writing_j1(book)
    first = VehicleStatus(
        vehicle_id="uav1", kind="q", state="writing", job_id="j1", incarnation="a"
    )
    book.status(first, 0.3)
    again = VehicleStatus(vehicle_id="uav1", kind="q", state="idle", incarnation="a")
    assert not book.status(again, 0.5).jobs  # the same agent: waits for the grace
    reborn = VehicleStatus(vehicle_id="uav1", kind="q", state="idle", incarnation="b")
    eff = book.status(reborn, 0.6)
    assert [e.message for e in eff.events if e.kind == "job_requeued"] == [
        "L: uav1 restarted without it"
    ]
    job = book.jobs["j1"]
    assert (job.state, job.attempts, job.handbacks) == ("queued", 1, 0)  # counted


def test_a_router_restart_costs_no_vehicle_if_its_clients_reconnect_within_the_grace() -> None:
    """The router dies at 1 s (every token goes, the orchestrator's link too) and is back 2.5 s
    later (a loaded host's supervisor). uav1 is back 1.4 s after the orchestrator's link,
    uav2 never: only uav2 is lost, 1.5 s after the link came back, not after its token went."""
    book = _book()
    _writing_j1(book)
    _online(book, "uav2", 0.0)
    _run(book, 0.2, 1.0, {"uav1": "j1", "uav2": None})
    book.router_link(False, 1.0)
    book.liveliness("uav1", False, 1.0)
    book.liveliness("uav2", False, 1.0)
    quiet = _run(book, 1.0, 3.5, {})
    assert [e.kind for e in quiet.events] == [] and not quiet.jobs  # nobody could be heard
    back = book.router_link(True, 3.5)
    assert [e.kind for e in back.events] == ["router_link"] and "2.5 s" in back.events[0].message
    merged = _run(book, 3.5, 4.9, {})
    book.liveliness("uav1", True, 4.9)
    merged.events += _run(book, 4.9, 6.0, {"uav1": "j1"}).events
    lost = [(e.vehicle_id, e.time_s) for e in merged.events if e.kind == "vehicle_lost"]
    assert lost == [("uav2", 5.0)]
    assert book.jobs["j1"].vehicle_id == "uav1" and book.jobs["j1"].state == "writing"


def test_without_the_router_link_a_lost_token_counts_from_when_it_went() -> None:
    book = _book()
    _writing_j1(book)
    book.liveliness("uav1", False, 1.0)
    merged = _run(book, 1.0, 2.6, {})
    assert [(e.vehicle_id, e.time_s) for e in merged.events if e.kind == "vehicle_lost"] == [
        ("uav1", 2.5)
    ]


def test_a_tracking_alert_is_raised_only_while_the_vehicle_writes() -> None:
    """An autopilot's take-off and transit lag its reference by 5-6 cm (SITL, issue 31): that
    spoils no character and was an alert at every take-off; with the brush down it is one."""
    book = _book()
    _online(book, "uav1", 0.0)
    for t_s in (1.0, 7.0, 13.0):
        assert book.telemetry("uav1", 0.08, "j1", t_s, writing=False).events == []
    said = book.telemetry("uav1", 0.08, "j1", 14.0, writing=True).events
    assert [(e.kind, e.level) for e in said] == [("limit", "alert")]
    assert "0.080 m" in said[0].message
    assert book.telemetry("uav1", 0.03, "j1", 20.0, writing=True).events == []  # within

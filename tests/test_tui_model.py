"""tui.model, tui.inbox, tui.tracks: the console's pure state, tested without Textual or Zenoh."""

from __future__ import annotations

import threading

import msgspec
import pytest
from hypothesis import given
from hypothesis import strategies as st

from bus.messages import (
    CommandReply,
    ErrorInfo,
    Event,
    JobState,
    OperatorCommand,
    ShowSnapshot,
    Telemetry,
    VehicleStatus,
    VehicleSummary,
)
from tui import format as fmt
from tui.format import job_totals_text
from tui.inbox import Inbox
from tui.inputs import BadPayload, OrchestratorPresence, VehiclePresence
from tui.model import ConsoleModel
from tui.settings import BoardGeometry, ConsoleSettings, VehicleSpec
from tui.throttle import RedrawThrottle
from tui.widgets.preview_pane import job_strokes

SETTINGS = ConsoleSettings(
    show_id="s",
    boards=(BoardGeometry("b1"),),
    vehicles=(VehicleSpec("uav2", "quadrotor-brush", "b1"), VehicleSpec("uav1", "q", "b1")),
    tracking_error_alert_m=0.05,
    lost_after_s=1.5,
)


def tm(
    vid: str = "uav1",
    *,
    state: str = "writing",
    error_m: float = 0.01,
    job_id: str | None = "j1",
    pen_down: bool = True,
    x: float = 0.0,
) -> Telemetry:
    return Telemetry(
        vehicle_id=vid,
        t_s=0.0,
        state=state,
        position_m_enu=(x, 0.0, 0.2),  # type: ignore[arg-type]
        velocity_mps_enu=(0.0, 0.0, 0.0),
        reference_m_enu=(x, 0.0, 0.2),
        pen_down=pen_down,
        tracking_error_m=error_m,
        battery_fraction=0.5,
        job_id=job_id,
        progress=0.25,
    )


def job(job_id: str, state: str, updated: float = 1.0, **extra: object) -> JobState:
    fields: dict[str, object] = {"kind": "text", **extra}
    return JobState(
        job_id=job_id,
        state=state,  # type: ignore[arg-type]
        label=job_id.upper(),
        client_id="c",
        created_at_s=updated,
        updated_at_s=updated,
        **fields,  # type: ignore[arg-type]
    )


def snapshot(
    jobs: list[JobState],
    vehicles: list[VehicleSummary] = (),
    time_s: float = 10.0,  # type: ignore[assignment]
    show_id: str = "s",
    paused: bool = False,
) -> ShowSnapshot:
    return ShowSnapshot(
        show_id=show_id, time_s=time_s, queue_paused=paused, jobs=jobs, vehicles=list(vehicles)
    )


def test_show_file_vehicles_are_listed_in_file_order_before_strangers() -> None:
    model = ConsoleModel(SETTINGS)
    model.apply(tm("aaa"), 0.0)
    assert model.vehicle_ids() == ["uav2", "uav1", "aaa"]
    assert model.vehicle_row("uav2", 0.0).state == "unknown"  # listed before any news


def test_telemetry_fills_the_row_and_link_age_grows_with_time() -> None:
    model = ConsoleModel(SETTINGS)
    model.apply(job("j1", "writing", vehicle_id="uav1"), 0.0)
    model.apply(tm(error_m=0.02), 100.0)
    row = model.vehicle_row("uav1", 100.5)
    assert (row.state, row.job_label, row.tracking_error_m, row.battery_fraction) == (
        "writing",
        "J1",
        0.02,
        0.5,
    )
    assert row.link_age_s == pytest.approx(0.5)
    assert not row.stale
    assert model.vehicle_row("uav1", 102.0).stale  # older than lost_after_s = 1.5 s


def test_tracking_error_alerts_only_while_writing_above_the_threshold() -> None:
    model = ConsoleModel(SETTINGS)
    model.apply(tm(error_m=0.049), 0.0)
    assert model.alerts() == []
    model.apply(tm(error_m=0.051), 0.0)
    assert [a.key for a in model.alerts()] == ["tracking:uav1"]
    assert "5.1 cm > 5.0 cm" in model.alerts()[0].message
    model.apply(tm(state="taking_off", error_m=0.3), 0.0)  # large errors off the board are normal
    assert model.alerts() == []


def test_a_vanished_token_makes_the_vehicle_lost_until_it_comes_back() -> None:
    model = ConsoleModel(SETTINGS)
    model.apply(VehiclePresence("uav1", alive=True), 0.0)
    model.apply(tm(), 0.0)
    model.apply(VehiclePresence("uav1", alive=False), 1.0)
    assert model.vehicle_row("uav1", 1.0).state == "lost"
    assert [a.key for a in model.alerts()] == ["lost:uav1"]
    model.apply(VehiclePresence("uav1", alive=True), 2.0)
    model.apply(VehicleStatus(vehicle_id="uav1", kind="q", state="idle"), 2.0)
    assert model.vehicle_row("uav1", 2.0).state == "idle"
    assert model.alerts() == []


def test_failed_jobs_alert_until_acknowledged_and_new_failures_alert_again() -> None:
    model = ConsoleModel(SETTINGS)
    failure = ErrorInfo(code="infeasible", message="too fast")
    model.apply(job("j1", "failed", error=failure), 0.0)
    assert "too fast" in model.alerts()[0].message
    assert model.acknowledge_alerts() == 1
    assert model.alerts() == []
    model.apply(job("j2", "failed", error=failure), 0.0)
    assert [a.key for a in model.alerts()] == ["failed:j2"]


def test_the_orchestrator_leaving_keeps_the_last_known_state() -> None:
    model = ConsoleModel(SETTINGS)
    model.apply(OrchestratorPresence(alive=True), 0.0)
    model.apply_snapshot(snapshot([job("j1", "queued", queue_position=1)]), 0.0, full=True)
    model.apply(OrchestratorPresence(alive=False), 5.0)
    assert model.orchestrator == "offline"
    assert model.job("j1") is not None
    assert [a.kind for a in model.alerts()] == ["orchestrator_lost"]
    assert model.events.after(0)[-1][1].kind == "orchestrator"
    model.apply(OrchestratorPresence(alive=True), 6.0)
    assert model.orchestrator == "online"
    assert model.events.after(0)[-1][1].message == "orchestrator back"


def test_an_older_job_state_never_overwrites_a_newer_one() -> None:
    model = ConsoleModel(SETTINGS)
    model.apply(job("j1", "writing", updated=5.0), 0.0)
    model.apply(job("j1", "queued", updated=4.0), 0.0)
    assert model.job("j1").state == "writing"


@given(st.permutations(list(range(6))))
def test_job_updates_in_any_arrival_order_end_in_the_newest(order: list[int]) -> None:
    states = ["submitted", "awaiting_approval", "queued", "assigned", "writing", "done"]
    model = ConsoleModel(SETTINGS)
    for i in order:
        model.apply(job("j1", states[i], updated=float(i)), 0.0)
    assert model.job("j1").state == "done"


def test_full_snapshot_keeps_newer_live_updates_and_drops_what_ended_before_it() -> None:
    model = ConsoleModel(SETTINGS)
    model.apply(job("j1", "writing", updated=12.0), 0.0)  # arrived live, after the snapshot
    model.apply(job("j2", "queued", updated=3.0), 0.0)  # stale: not in the snapshot any more
    model.apply_snapshot(
        snapshot([job("j1", "queued", updated=9.0), job("j3", "done", updated=8.0)], time_s=10.0),
        0.0,
        full=True,
    )
    assert model.job("j1").state == "writing"
    assert model.job("j2") is None
    assert model.job("j3").state == "done"


def test_a_listed_job_left_out_of_a_newer_fleet_publication_ended_unheard() -> None:
    model = ConsoleModel(SETTINGS)
    listed = [job(j, "queued", updated=4.0) for j in ("j1", "j2", "j4")]
    model.apply(snapshot(listed, time_s=4.5), 0.0)  # a fleet publication
    assert model.ended_unheard == set()
    model.apply(job("j1", "writing", updated=5.0), 0.0)  # its "done" message never came
    model.apply(job("j2", "queued", updated=12.0), 0.0)  # newer than the publication below
    model.apply(job("j3", "done", updated=6.0), 0.0)  # finished: never listed in fleet
    model.apply(job("j4", "queued", updated=7.0), 0.0)
    model.apply(job("rogue", "writing", updated=3.0), 0.0)  # never listed: not the orchestrator's
    model.apply(snapshot([job("j4", "assigned", updated=9.0)], time_s=10.0), 0.0)  # fleet
    assert model.ended_unheard == {"j1"}
    assert model.job("j1").state == "writing"  # the console asks the orchestrator (app.py)
    model.apply_snapshot(snapshot([job("j1", "done", updated=8.0)], time_s=11.0), 0.0, full=True)
    assert model.ended_unheard == set() and model.job("j1").state == "done"


def test_a_drawings_strokes_survive_messages_without_them_and_reach_the_preview() -> None:
    strokes = {"units": "m", "y_axis": "up", "strokes": [[[0.0, 0.0], [1.0, 1.0]]]}
    model = ConsoleModel(SETTINGS)
    model.apply(job("j1", "awaiting_approval", updated=1.0, kind="strokes", strokes=strokes), 0.0)
    model.apply(snapshot([job("j1", "awaiting_approval", updated=1.0, kind="strokes")]), 0.5)
    model.apply(job("j1", "assigned", updated=2.0, kind="strokes"), 1.0)
    model.apply_snapshot(
        snapshot([job("j1", "writing", updated=3.0, kind="strokes")]), 2.0, full=True
    )
    kept = model.job("j1")
    assert kept is not None and kept.state == "writing" and kept.strokes == strokes
    assert job_strokes(kept) == strokes
    model.apply(job("j2", "queued", updated=4.0), 3.0)
    other = model.job("j2")
    assert other is not None and other.strokes is None


def test_fleet_summary_yields_to_the_vehicles_own_recent_word_except_for_lost() -> None:
    model = ConsoleModel(SETTINGS)
    model.apply(tm(state="returning"), 10.0)
    idle = VehicleSummary(vehicle_id="uav1", kind="q", state="idle", alive=True)
    model.apply_snapshot(snapshot([], [idle]), 10.5, full=False)
    assert model.vehicle_row("uav1", 10.5).state == "returning"
    model.apply_snapshot(snapshot([], [idle]), 20.0, full=False)  # the vehicle went quiet
    assert model.vehicle_row("uav1", 20.0).state == "idle"
    lost = VehicleSummary(vehicle_id="uav1", kind="q", state="lost", alive=False)
    model.apply(tm(state="writing"), 30.0)
    model.apply_snapshot(snapshot([], [lost]), 30.1, full=False)
    assert model.vehicle_row("uav1", 30.1).state == "lost"


def test_a_snapshot_of_another_show_is_ignored_and_logged() -> None:
    model = ConsoleModel(SETTINGS)
    model.apply_snapshot(snapshot([job("j1", "queued")], show_id="other"), 0.0, full=True)
    assert model.job("j1") is None
    assert model.events.after(0)[-1][1].kind == "bad_message"


def test_queue_rows_come_in_sections_and_queue_order() -> None:
    model = ConsoleModel(SETTINGS)
    for j in [
        job("d1", "done", updated=1.0),
        job("d2", "done", updated=2.0),
        job("q2", "queued", queue_position=2),
        job("q1", "queued", queue_position=1),
        job("w1", "writing", vehicle_id="uav1"),
        job("a1", "awaiting_approval"),
        job("f1", "failed"),
        job("c1", "cancelled"),
    ]:
        model.apply(j, 0.0)
    rows = [(r.section, r.job.job_id) for r in model.queue_rows()]
    assert rows[:4] == [("awaiting", "a1"), ("queued", "q1"), ("queued", "q2"), ("active", "w1")]
    assert rows[4:6] == [("done", "d2"), ("done", "d1")]  # newest first
    assert {r for r in rows[6:]} == {("failed", "f1"), ("failed", "c1")}


def test_finished_jobs_are_bounded_oldest_first() -> None:
    model = ConsoleModel(SETTINGS, max_finished=3)
    for i in range(5):
        model.apply(job(f"j{i}", "done", updated=float(i)), 0.0)
    model.apply(job("q", "queued"), 0.0)
    assert [r.job.job_id for r in model.queue_rows()] == ["q", "j4", "j3", "j2"]


def test_job_totals_come_from_the_orchestrators_counts_not_the_bounded_list() -> None:
    model = ConsoleModel(SETTINGS, max_finished=100)
    finished = [job(f"j{i}", "done", updated=float(i)) for i in range(600)]
    full = msgspec.structs.replace(
        snapshot(finished[-500:]), job_counts={"done": 600, "failed": 4, "queued": 1}
    )
    model.apply_snapshot(full, 10.0, full=True)
    assert len(model.queue_rows()) == 100  # the list stays bounded
    assert job_totals_text(model.job_counts) == "; 600 done, 4 failed"
    version = model.status_version
    fleet = msgspec.structs.replace(snapshot([], time_s=11.0), job_counts={"done": 601})
    model.apply(fleet, 11.0)  # a fleet publication carries the totals too
    assert job_totals_text(model.job_counts) == "; 601 done"
    assert model.status_version > version  # the header redraws
    assert job_totals_text({}) == ""  # nothing said before the first count


def test_refused_commands_and_bad_payloads_are_logged() -> None:
    model = ConsoleModel(SETTINGS)
    model.record_command(
        OperatorCommand(command="land", vehicle_id="uav1"), CommandReply(ok=True, message="ok"), 1.0
    )
    assert model.events.after(0) == []  # the orchestrator logs accepted commands itself
    refused = CommandReply(ok=False, error=ErrorInfo(code="no_answer", message="no answer"))
    model.record_command(OperatorCommand(command="land", vehicle_id="uav1"), refused, 1.5)
    model.apply(BadPayload("skyquill/s/events", "not valid JSON"), 2.0)
    events = [e for _, e in model.events.after(0)]
    assert (events[0].kind, events[0].message, events[0].vehicle_id) == (
        "command",
        "land uav1 -> no answer",
        "uav1",
    )
    assert events[1].level == "warning" and "not valid JSON" in events[1].message
    assert model.last_reply == (OperatorCommand(command="land", vehicle_id="uav1"), refused)


def test_event_log_is_bounded_and_sequenced() -> None:
    model = ConsoleModel(SETTINGS, max_events=3)
    for i in range(5):
        model.apply(Event(time_s=float(i), level="info", kind="k", message=str(i)), 0.0)
    assert [e.message for _, e in model.events.after(0)] == ["2", "3", "4"]
    assert [e.message for _, e in model.events.after(4)] == ["4"]


def test_tracks_restart_with_a_new_job_and_ignore_samples_without_one() -> None:
    model = ConsoleModel(SETTINGS)
    for i in range(3):
        model.apply(tm(job_id="j1", x=0.1 * i), 0.0)
    model.apply(tm(job_id=None, state="returning"), 0.0)
    track = model.track("uav1")
    assert (track.job_id, track.count, track.generation) == ("j1", 3, 1)
    model.apply(tm(job_id="j2"), 0.0)
    assert (track.job_id, track.count, track.generation) == ("j2", 1, 2)


def test_redraws_are_throttled_while_busy_and_kept_alive_while_idle() -> None:
    throttle = RedrawThrottle(rate_hz=4.0, idle_s=0.5)  # binary fractions: exact arithmetic
    frames = [t / 64 for t in range(64) if throttle.due(t / 64, dirty=True)]
    assert frames == [0.0, 0.25, 0.5, 0.75]  # 1 s of constant change at 4 Hz
    assert not throttle.due(1.0, dirty=False)  # nothing changed: wait for the idle period
    assert throttle.due(1.25, dirty=False)  # ages on screen must still move
    assert not throttle.due(1.25 + 1 / 64, dirty=True)
    assert throttle.due(1.5, dirty=True)


def test_inbox_keeps_arrival_order_and_drops_only_the_oldest_droppable_items() -> None:
    inbox: Inbox[str] = Inbox(lambda s: s.startswith("t"), max_droppable=2)
    wakes = [inbox.put(s) for s in ["t1", "job1", "t2", "t3", "job2"]]
    assert wakes == [True, False, False, False, False]
    assert inbox.drain() == ["job1", "t2", "t3", "job2"]
    assert inbox.dropped == 1
    assert inbox.put("t4") is True  # empty again: wake the consumer


def test_inbox_loses_nothing_undroppable_across_threads() -> None:
    inbox: Inbox[int] = Inbox(lambda n: n < 0)
    got: list[int] = []

    def produce(base: int) -> None:
        for i in range(2000):
            inbox.put(base + i)

    threads = [threading.Thread(target=produce, args=(k * 10_000,)) for k in range(4)]
    for t in threads:
        t.start()
    while any(t.is_alive() for t in threads):
        got.extend(inbox.drain())
    for t in threads:
        t.join()
    got.extend(inbox.drain())
    assert sorted(got) == sorted(k * 10_000 + i for k in range(4) for i in range(2000))
    for k in range(4):  # each producer's items stay in its order
        mine = [n for n in got if k * 10_000 <= n < (k + 1) * 10_000]
        assert mine == sorted(mine)


def ev(time_s: float, message: str) -> Event:
    return Event(time_s=time_s, level="info", kind="operator", message=message)


def test_a_late_joiner_gets_recent_history_from_the_snapshot_once() -> None:
    m = ConsoleModel(SETTINGS)
    m.events.note(5.0, "info", "console", "console's own note")  # never hides the show's history
    with_history = msgspec.structs.replace(snapshot([]), events=[ev(1.0, "a"), ev(2.0, "b")])
    m.apply_snapshot(with_history, 10.0, full=True)
    m.apply(ev(3.0, "c"), 10.5)  # live
    m.apply_snapshot(  # asked again (the orchestrator came back): nothing twice
        msgspec.structs.replace(snapshot([]), events=[ev(2.0, "b"), ev(3.0, "c"), ev(4.0, "d")]),
        11.0,
        full=True,
    )
    m.apply_snapshot(msgspec.structs.replace(snapshot([]), events=[ev(9.0, "x")]), 12, full=False)
    shown = [e.message for _, e in m.events.after(0)]
    assert shown == ["console's own note", "a", "b", "c", "d"]  # fleet publications add none


def test_held_faulted_and_flying_vehicles_are_counted_for_the_header_and_quit() -> None:
    m = ConsoleModel(SETTINGS)
    m.apply(tm("uav1", state="writing"), 1.0)
    m.apply(tm("uav2", state="idle", job_id=None), 1.0)
    assert (m.airborne_count(), m.can_fly_count()) == (1, 2)
    held = VehicleSummary(vehicle_id="uav2", kind="q", state="landed", alive=True, held=True)
    m.apply_snapshot(snapshot([], [held]), 1.0, full=False)
    assert m.vehicle_row("uav2", 1.0).held and m.can_fly_count() == 1  # type: ignore[union-attr]
    m.apply(tm("uav1", state="fault"), 2.0)
    assert m.can_fly_count() == 0 and m.fault_ids() == ["uav1"] and m.airborne_count() == 0
    assert "uav1 fault" in [a.message for a in m.alerts()]


def test_waiting_submissions_alert_and_a_new_one_alerts_again_after_acknowledging() -> None:
    m = ConsoleModel(SETTINGS)
    m.apply(job("j1", "awaiting_approval", 1.0), 1.0)
    assert [a.message for a in m.alerts()] == ["1 submission(s) awaiting approval"]
    assert m.acknowledge_alerts() == 1 and m.alerts() == []
    m.apply(job("j2", "awaiting_approval", 2.0), 2.0)
    assert [a.message for a in m.alerts()] == ["2 submission(s) awaiting approval"]
    assert m.awaiting_count() == 2


def test_rejected_and_cancelled_jobs_read_as_such_not_as_failed() -> None:
    m = ConsoleModel(SETTINGS)
    reason = ErrorInfo(code="rejected", message="not a letter")
    m.apply(job("j1", "rejected", 1.0, error=reason), 1.0)
    m.apply(job("j2", "cancelled", 2.0), 1.0)
    m.apply(job("j3", "failed", 3.0), 1.0)
    labels = {r.job.job_id: (fmt.section_text(r).plain, fmt.job_detail(r)) for r in m.queue_rows()}
    assert labels == {
        "j1": ("rejected", "not a letter"),
        "j2": ("cancelled", "cancelled"),
        "j3": ("failed", "failed"),
    }

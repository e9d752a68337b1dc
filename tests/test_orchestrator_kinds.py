"""The orchestrator gives a job only to a vehicle whose kind can write it: a kind whose planner
refused a job never gets it again while another kind may still write it, a vehicle that cannot
reach its board gets no job at all, and the ETAs follow the same rule."""

from __future__ import annotations

from pathlib import Path

from bus.messages import AgentReport, ErrorInfo, SubmitRequest, VehicleStatus
from orchestrator.core import Book, CoreConfig, Effects
from orchestrator.fleet import EtaModel, VehicleInfo, queue_etas
from orchestrator.kinds import KindPlans
from orchestrator.outputs import core_config
from orchestrator.submissions import planned_durations_s
from planner.glyphs import parse_strokes_json
from showfile import load_show, parse_show

SHOWS = Path(__file__).resolve().parents[1] / "shows"
WALL = VehicleInfo("hex1", "hexarotor-sponge", "wall")
QUAD = VehicleInfo("uav1", "quadrotor-brush", "b1")
WIDTH_ERROR = ErrorInfo(code="plan_failed", message="stroke 0: width 30 mm outside 5-14 mm")


def _online(book: Book, info: VehicleInfo, now: float) -> Effects:
    eff = book.liveliness(info.vehicle_id, True, now)
    status = VehicleStatus(vehicle_id=info.vehicle_id, kind=info.kind, state="idle")
    more = book.status(status, now)
    eff.commands += more.commands
    return eff


def _assigned(eff: Effects) -> list[tuple[str, str]]:
    return [(vid, c.job.job_id) for vid, c in eff.commands if c.command == "assign" and c.job]


def _submit(book: Book, job_id: str, now: float) -> Effects:
    request = SubmitRequest(text="A")
    reply, eff = book.submit(job_id, request, label="A", estimate_s=20.0, now_s=now)
    assert reply.ok
    return eff


def _refuse(book: Book, vehicle: str, job_id: str, now: float) -> Effects:
    report = AgentReport(vehicle_id=vehicle, job_id=job_id, event="failed", error=WIDTH_ERROR)
    reply, eff = book.report(report, now)
    assert reply.ok
    return eff


def test_a_job_one_kind_cannot_plan_waits_for_a_vehicle_of_another_kind() -> None:
    book = Book(CoreConfig(show_id="t", vehicles=(WALL, QUAD)), now_s=0.0)
    _online(book, WALL, 0.0)
    assert _assigned(_submit(book, "j1", 0.0)) == [("hex1", "j1")]
    _refuse(book, "hex1", "j1", 1.0)
    job = book.jobs["j1"]
    assert job.state == "queued" and job.counted_attempts == 0, job  # not lost, not counted
    for t in (2.0, 3.0, 4.0):
        assert _assigned(book.tick(t)) == []  # the hexarotor, idle again, never gets it back
    assert book.etas(4.0)["j1"] == (1, None)  # no usable vehicle may take it: no ETA
    got = _assigned(_online(book, QUAD, 5.0)) + _assigned(book.tick(5.1))
    assert got == [("uav1", "j1")]
    assert book.etas(5.1) == {}
    assert _assigned(_submit(book, "j2", 6.0)) == [("hex1", "j2")]  # others still go to the wall


def test_a_job_every_kind_refused_fails_with_the_planner_reason() -> None:
    book = Book(CoreConfig(show_id="t", vehicles=(WALL, QUAD)), now_s=0.0)
    _online(book, WALL, 0.0)
    assert _assigned(_submit(book, "j1", 0.0)) == [("hex1", "j1")]
    _refuse(book, "hex1", "j1", 1.0)
    _online(book, QUAD, 2.0)
    book.tick(2.1)
    assert book.jobs["j1"].vehicle_id == "uav1"
    _refuse(book, "uav1", "j1", 3.0)
    job = book.jobs["j1"]
    assert job.state == "failed" and job.error == WIDTH_ERROR
    assert "j1" not in book.kinds.refused


def test_a_kind_whose_planner_refused_the_job_for_its_eta_is_never_sent_it() -> None:
    book = Book(CoreConfig(show_id="t", vehicles=(WALL, QUAD)), now_s=0.0)
    _submit(book, "j1", 0.0)  # nobody online yet
    book.set_estimate("j1", KindPlans({"quadrotor-brush": 12.0}, frozenset({WALL.kind})), 0.5)
    assert book.jobs["j1"].estimate_s == 12.0
    assert _assigned(_online(book, WALL, 1.0)) + _assigned(book.tick(1.1)) == []
    assert _assigned(_online(book, QUAD, 2.0)) + _assigned(book.tick(2.1)) == [("uav1", "j1")]


def test_a_job_every_kind_refused_for_its_eta_is_left_to_a_vehicle_to_fail_with_the_reason() -> (
    None
):
    book = Book(CoreConfig(show_id="t", vehicles=(WALL, QUAD)), now_s=0.0)
    _submit(book, "j1", 0.0)
    book.set_estimate("j1", KindPlans({}, frozenset({WALL.kind, QUAD.kind})), 0.5)
    assert "j1" not in book.kinds.refused
    assert _assigned(_online(book, WALL, 1.0)) + _assigned(book.tick(1.1)) == [("hex1", "j1")]


def test_the_eta_planning_names_the_kinds_that_cannot_plan_a_glyph() -> None:
    show = load_show(SHOWS / "mixed.yaml")
    wide = [{"x": 0.0, "y": 0.0, "w": 0.03}, {"x": 0.3, "y": 0.0, "w": 0.03}]  # 30 mm: no pen
    plans = planned_durations_s(
        parse_strokes_json({"units": "m", "y_axis": "up", "strokes": [wide]}), show
    )
    assert plans.refused == {"hexarotor-sponge"}
    assert "quadrotor-brush" in plans.durations_s and "hexarotor-sponge" not in plans.durations_s


GROUND = """\
show_id: t
omni_wheel:
  steps: [{x_m: 1.5, height_m: 0.05}]
boards:
  - {id: plaza, orientation: floor, center_m_enu: [3.5, 0, 0.05], size_m: [2, 2],
     writing_area_m: [1.8, 1.8]}
vehicles:
  - {id: ground1, kind: omni-wheel, board: plaza, home_m_enu: [0, 0, 0]}
"""


def test_a_vehicle_that_cannot_reach_its_floor_area_is_never_given_a_job() -> None:
    show = parse_show(GROUND)
    assert core_config(show).vehicles[0].cannot_write is None
    # the show file refuses the higher step; a show built in code (past validation) still
    # keeps the job in the queue rather than send the vehicle
    steep = show.omni_wheel.model_copy(update={"steps": ()}) if show.omni_wheel else None
    board = show.boards[0].model_copy(update={"center_m_enu": (3.5, 0.0, 0.3)})
    bad = show.model_copy(update={"omni_wheel": steep, "boards": (board,)})
    (info,) = core_config(bad).vehicles
    assert info.cannot_write is not None and "'plaza'" in info.cannot_write
    book = Book(CoreConfig(show_id="t", vehicles=(info,)), now_s=0.0)
    _online(book, info, 0.0)
    assert _assigned(_submit(book, "j1", 0.0)) + _assigned(book.tick(1.0)) == []
    assert book.jobs["j1"].state == "queued"


def test_etas_take_the_duration_of_the_kind_that_would_write_each_job() -> None:
    ground = VehicleInfo("ground1", "omni-wheel", "plaza")
    book = Book(CoreConfig(show_id="t", vehicles=(QUAD, ground)), now_s=0.0)
    for job_id in ("j1", "j2", "j3"):
        _submit(book, job_id, 0.0)  # rough estimate 20 s each
        book.set_estimate(job_id, KindPlans({"quadrotor-brush": 10.0, "omni-wheel": 60.0}), 0.0)
    assert book.jobs["j1"].estimate_s == 10.0  # the first vehicle's kind
    model = EtaModel(before_write_s=11.0, after_write_s=9.0)
    usable = {"uav1": "b1", "ground1": "plaza"}
    kinds = book.kinds
    etas = queue_etas(book.queue(), [], usable, 0.0, model, may_take=kinds.may_take,
                      writing_s_on=kinds.writing_s_on)  # fmt: skip
    # j1 on ground1 (60 s, free at 80), j2 on uav1 (10 s, free at 30): j3 next on uav1
    assert etas == {"j1": 11.0, "j2": 11.0, "j3": 41.0}
    kinds.refuse("j2", "uav1", book.config.vehicles)  # the brush cannot plan j2
    etas = queue_etas(book.queue(), [], usable, 0.0, model, may_take=kinds.may_take,
                      writing_s_on=kinds.writing_s_on)  # fmt: skip
    # j1 on ground1, j2 must wait for ground1 (free at 80), j3 on uav1 at once
    assert etas == {"j1": 11.0, "j2": 91.0, "j3": 11.0}

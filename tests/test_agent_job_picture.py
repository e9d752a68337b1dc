"""Every flown job gets its ``report.png``: a burst is queued, not skipped; orders beyond the
queue and those a stopped agent left behind are drawn from disk; a compact job with its picture
stays under 100 kB, the picture readable (1280 px wide)."""

from __future__ import annotations

import logging
import os
import threading
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from job_traces import recorded_trace, solo_job
from PIL import Image

from bus.messages import JobAssignment
from vehicle_agent.job_files import directory_bytes
from vehicle_agent.job_picture import (
    FAILED_NAME,
    ORDER_NAME,
    PICTURE_NAME,
    PICTURE_NICE_STEP,
    PictureOrder,
    PictureWorker,
    main,
    write_order,
)
from vehicle_agent.jobs import (
    job_glyph,
    job_label,
    job_metrics,
    picture_order,
    picture_title,
    prepare_job,
    write_job_report,
    writing_plan,
)
from vehicle_agent.setup import VehicleSetup
from vehicle_agent.trace import JobTrace
from vehicles.registry import vehicle_kind

DRAW_DEADLINE_S = 240.0
"""Wall time allowed for a few pictures (about a second of CPU each) on a loaded machine."""


def _flown_as_planned(setup: VehicleSetup, prepared: object, job_id: str) -> JobTrace:
    """``prepared`` flown exactly, the brush 0.25 m under the body (solo's brush lever)."""
    s = prepared.samples  # type: ignore[attr-defined]
    tip = s.position_m_enu - np.array([0.0, 0.0, 0.25])
    width = np.where(s.pen_down, 0.02, 0.0)
    args = (job_id, 1, s.t_s, s.position_m_enu, s.velocity_mps_enu, s.position_m_enu, s.pen_down)
    return recorded_trace(*args, s.pen_down.copy(), tip, width)


@pytest.fixture(scope="module")
def one_order(tmp_path_factory: pytest.TempPathFactory) -> PictureOrder:
    setup, prepared = solo_job(tmp_path_factory.mktemp("solo"), "compact")
    order = picture_order(setup, prepared, _flown_as_planned(setup, prepared, "j1"))
    assert order is not None
    return order


def test_a_job_picture_is_titled_by_its_character_and_says_when_it_was_broken_off(
    one_order: PictureOrder, tmp_path: Path
) -> None:
    """The title names what was written (the typed text, or ``drawing (N strokes)``), as the
    operator and the visitor know the job, before its id; the figure draws it literally."""
    assert one_order.title.startswith("一 · job j1 on uav1, attempt 1")
    figure = vehicle_kind(one_order.kind).report(
        one_order.plan, one_order.flown, one_order.settings, one_order.title
    )
    heading = figure.get_suptitle()
    assert "一" in heading or "U+4E00" in heading  # spelt out where no CJK font is installed
    setup, prepared = solo_job(tmp_path, "compact")
    half = _flown_as_planned(setup, prepared, "j1")
    keep = half.flown.t_s <= 0.5 * prepared.samples.duration_s
    cut = recorded_trace(
        "j1", 1, half.flown.t_s[keep], half.flown.base_m_enu[keep],  # type: ignore[index]
        half.flown.extra["velocity_mps_enu"][keep], half.flown.reference_m_enu[keep],
        half.flown.pen_down[keep], half.flown.pen_down[keep],
        half.flown.writing_point_m_enu[keep], half.flown.ink_width_m[keep],
    )  # fmt: skip
    broken = replace(cut, flown=replace(cut.flown, abort_reason="deviation"))
    assert picture_title(setup, prepared, broken).endswith(
        "attempt 1, aborted for deviation at 50% of its plan"
    )
    long = replace(prepared, label="永\n" + "x" * 80)  # one line, cut: the job's id stays in
    assert picture_title(setup, long, half).startswith(f"永 {'x' * 35}... · job j1 on uav1")
    drawn = JobAssignment(job_id="j2", strokes={"units": "m", "y_axis": "up", "strokes": [[
        {"x": 0.0, "y": 0.0}, {"x": 0.1, "y": 0.0}]]})  # fmt: skip
    assert job_label(drawn, job_glyph(drawn)) == "drawing (1 stroke)"


def _job_dirs(jobs: Path, n: int, first: int = 0) -> list[Path]:
    dirs = [jobs / f"j{i}-uav1-1" for i in range(first, first + n)]
    for d in dirs:
        d.mkdir(parents=True)
    return dirs


def _pictured(dirs: list[Path]) -> list[bool]:
    return [(d / PICTURE_NAME).is_file() and not (d / ORDER_NAME).exists() for d in dirs]


def test_a_burst_of_finished_jobs_gets_every_picture_and_the_backlog_is_told(
    tmp_path: Path, one_order: PictureOrder, caplog: pytest.LogCaptureFixture
) -> None:
    worker = PictureWorker("uav1")
    dirs = _job_dirs(tmp_path / "jobs", 5)
    with caplog.at_level(logging.WARNING, logger="vehicle_agent.job_picture"):
        for d in dirs:  # all at once: before, the first was drawn and the others skipped
            worker.submit(d, one_order)
        assert worker.wait(DRAW_DEADLINE_S)
    assert _pictured(dirs) == [True] * 5 and worker.drawn == 5 and worker.waiting == 0
    threads = [t.native_id for t in threading.enumerate() if t.name == "pictures-uav1"]
    own = os.getpriority(os.PRIO_PROCESS, 0)  # below the planning that shares its process:
    niced = [os.getpriority(os.PRIO_PROCESS, tid) - own for tid in threads if tid is not None]
    assert niced and set(niced) == {PICTURE_NICE_STEP}
    with Image.open(dirs[0] / PICTURE_NAME) as image:
        assert image.mode == "P" and image.width >= 1200  # compact: a 1280 px palette picture
    assert [r.getMessage() for r in caplog.records] == [
        "uav1: 4 job pictures wait to be drawn (the machine is busy); each will be drawn"
    ]


def test_orders_beyond_the_queue_and_from_a_stopped_agent_are_drawn(
    tmp_path: Path, one_order: PictureOrder
) -> None:
    jobs = tmp_path / "jobs"
    left = _job_dirs(jobs, 1)  # ordered by an agent that stopped before drawing them
    for d in left:
        write_order(d, one_order)
    other = jobs / "j9-uav2-1"  # another vehicle's: not this worker's
    other.mkdir()
    write_order(other, one_order)
    worker = PictureWorker("uav1", capacity=1)
    new = _job_dirs(jobs, 2, first=1)
    for d in new:
        worker.submit(d, one_order)
    assert worker.wait(DRAW_DEADLINE_S)
    assert _pictured(left + new) == [True] * 3 and worker.drawn == 3
    assert (other / ORDER_NAME).exists() and not (other / PICTURE_NAME).exists()


def test_an_order_that_cannot_be_drawn_is_set_aside_and_the_rest_are_drawn(
    tmp_path: Path, one_order: PictureOrder, caplog: pytest.LogCaptureFixture
) -> None:
    bad, good = _job_dirs(tmp_path / "jobs", 2)
    (bad / ORDER_NAME).write_bytes(b"not a pickle")
    worker = PictureWorker("uav1")
    with caplog.at_level(logging.ERROR, logger="vehicle_agent.job_picture"):
        worker.submit(good, one_order)
        assert worker.wait(DRAW_DEADLINE_S)
    assert (bad / FAILED_NAME).exists() and not (bad / ORDER_NAME).exists()
    assert _pictured([good]) == [True] and "j0-uav1-1" in caplog.text


def test_a_compact_job_with_its_picture_stays_under_100_kb(tmp_path: Path) -> None:
    """永 flown in the brush quadrotor's simulation (its noise, not a perfect trace) and
    recorded as the agent records it: metrics, flight, reference and picture together."""
    setup, _ = solo_job(tmp_path, "compact")
    prepared = prepare_job(setup, JobAssignment(job_id="j2", text="永"))
    flown = setup.kind.fly(writing_plan(prepared), setup.settings)
    assert flown.base_m_enu is not None
    trace = recorded_trace(
        "j2",
        1,
        flown.t_s,
        flown.base_m_enu,
        flown.extra["velocity_mps_enu"],
        flown.reference_m_enu,
        flown.pen_down,
        flown.ink_width_m > 0.0,
        flown.writing_point_m_enu,
        flown.ink_width_m,
    )
    out = write_job_report(setup, prepared, trace, job_metrics(setup, prepared, trace))
    worker = PictureWorker("uav1")
    order = picture_order(setup, prepared, trace)
    assert order is not None
    worker.submit(out, order)
    assert worker.wait(DRAW_DEADLINE_S)
    assert sorted(p.name for p in out.iterdir()) == ["flight.npz", "metrics.json", PICTURE_NAME]
    with Image.open(out / PICTURE_NAME) as image:
        assert image.width >= 1200
    assert directory_bytes(out) < 100_000


def test_orders_left_after_a_show_are_drawn_by_the_command(
    tmp_path: Path, one_order: PictureOrder, capsys: pytest.CaptureFixture[str]
) -> None:
    jobs = tmp_path / "jobs"
    (left,) = _job_dirs(jobs, 1)
    write_order(left, one_order)
    assert main([str(jobs)]) == 0 and _pictured([left]) == [True]
    assert capsys.readouterr().out.strip() == str(left / PICTURE_NAME)
    assert main([str(tmp_path / "nowhere")]) == 2
    assert capsys.readouterr().err == "usage: python -m vehicle_agent.job_picture JOBS_DIR\n"

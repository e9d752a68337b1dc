"""Pictures drawn in a process apart (``vehicle_agent/picture_process.py``): a drawing process
that dies on an order costs that order alone (set aside as ``picture.failed``, said in the log);
the orders after it in its batch are drawn by the next process, none is skipped. One drawing
process runs at a time per host: a vehicle's pictures wait while another's are drawn."""

from __future__ import annotations

import logging
import os
import pickle
import time
from pathlib import Path

import pytest
from job_traces import solo_job
from test_agent_job_picture import DRAW_DEADLINE_S, _flown_as_planned, _job_dirs, _pictured

from vehicle_agent.job_picture import FAILED_NAME, ORDER_NAME, PictureOrder, PictureWorker
from vehicle_agent.jobs import picture_order
from vehicle_agent.picture_process import drawing_turn


@pytest.fixture(scope="module")
def one_order(tmp_path_factory: pytest.TempPathFactory) -> PictureOrder:
    setup, prepared = solo_job(tmp_path_factory.mktemp("solo"), "compact")
    order = picture_order(setup, prepared, _flown_as_planned(setup, prepared, "j1"))
    assert order is not None
    return order


class _KillsItsReader:
    """Unpickled, it ends the process that reads it at once (as a crash in drawing would)."""

    def __reduce__(self) -> tuple[object, tuple[int]]:
        return os._exit, (3,)


def test_a_drawing_process_that_dies_costs_only_its_order(
    tmp_path: Path,
    one_order: PictureOrder,
    caplog: pytest.LogCaptureFixture,
) -> None:
    deadly, *good = _job_dirs(tmp_path / "jobs", 3)
    (deadly / ORDER_NAME).write_bytes(pickle.dumps(_KillsItsReader()))  # the oldest: first
    worker = PictureWorker("uav1")
    with caplog.at_level(logging.ERROR, logger="vehicle_agent.job_picture"):
        for job_dir in good:
            worker.submit(job_dir, one_order)
        assert worker.wait(DRAW_DEADLINE_S)
    assert _pictured(good) == [True, True] and worker.drawn == 2
    assert (deadly / FAILED_NAME).exists() and not (deadly / ORDER_NAME).exists()
    assert "died (code 3) on the picture of j0-uav1-1" in caplog.text
    assert worker.drawing_cpu_s > 0.0


def test_pictures_wait_for_the_hosts_turn_to_draw(tmp_path: Path, one_order: PictureOrder) -> None:
    jobs = tmp_path / "jobs"
    dirs = _job_dirs(jobs, 2)
    worker = PictureWorker("uav1")
    with drawing_turn(jobs):  # another vehicle's pictures are being drawn
        for job_dir in dirs:
            worker.submit(job_dir, one_order)
        time.sleep(2.0)  # a drawing process of its own would have drawn the first by now
        assert _pictured(dirs) == [False, False] and worker.drawn == 0
    assert worker.wait(DRAW_DEADLINE_S)
    assert _pictured(dirs) == [True, True] and worker.drawn == 2

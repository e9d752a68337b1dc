"""The journal of results not yet answered (``vehicle_agent/results.py``), on a real disk."""

from __future__ import annotations

from pathlib import Path

from bus.messages import AgentReport
from vehicle_agent.results import ResultJournal


def test_a_result_is_kept_from_the_last_ink_until_answered_and_survives_a_new_journal(
    tmp_path: Path,
) -> None:
    journal = ResultJournal("uav1", tmp_path)
    journal.written("j1", 12.5)
    again = ResultJournal("uav1", tmp_path).recover()  # killed before measuring
    assert [(r.event, r.progress, r.error and r.error.code) for r in again] == [
        ("failed", 1.0, "unmeasured")
    ]
    done = AgentReport(vehicle_id="uav1", job_id="j1", event="done", progress=1.0)
    journal.measured(done)
    later = ResultJournal("uav1", tmp_path)
    assert later.recover() == [done] and later.pending() == "j1" and later.unsettled("j1")
    later.settled("j1")
    assert later.pending() is None and not list(tmp_path.iterdir())


def test_a_job_id_that_is_no_file_name_is_hashed_and_a_torn_file_skipped(tmp_path: Path) -> None:
    journal = ResultJournal("uav1", tmp_path)
    journal.written("../../etc/passwd", 3.0)
    (name,) = [p.name for p in tmp_path.iterdir()]
    assert name.endswith(".json") and len(name) == 64 + 5  # inside the folder, whatever the id
    (tmp_path / "j9.json").write_bytes(b'{"vehicle_id": "uav1", "job')  # a disk that filled
    assert [r.job_id for r in ResultJournal("uav1", tmp_path).recover()] == ["../../etc/passwd"]


def test_without_a_folder_the_journal_keeps_results_in_memory() -> None:
    journal = ResultJournal("uav1", None)
    journal.written("j1", 3.0)
    assert journal.pending() == "j1" and ResultJournal("uav1", None).recover() == []

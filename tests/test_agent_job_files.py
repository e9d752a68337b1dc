"""A vehicle's job directories: compact flights, and pruning to its share of the show's budget."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from showfile import load_show
from vehicle_agent.job_files import JobFilesPolicy, decimated, prune, written_whole

SHOWS = Path(__file__).resolve().parents[1] / "shows"


def _job_dir(jobs: Path, name: str, size_bytes: int, mtime_s: float) -> Path:
    path = jobs / name
    path.mkdir(parents=True)
    (path / "flight.npz").write_bytes(b"x" * size_bytes)
    os.utime(path, (mtime_s, mtime_s))
    return path


def test_the_oldest_of_a_vehicles_own_jobs_go_first_and_never_the_newest(tmp_path: Path) -> None:
    jobs = tmp_path / "jobs"
    mine = [_job_dir(jobs, f"j{i}-uav1-1", 400, 1000.0 + i) for i in range(5)]
    theirs = _job_dir(jobs, "j9-uav2-1", 5000, 900.0)
    removed = prune(jobs, "uav1", JobFilesPolicy(budget_bytes=1000), now_s=2000.0)
    assert sorted(removed) == mine[:3]  # the newest two fit in 1000 bytes
    assert [p.exists() for p in mine] == [False, False, False, True, True] and theirs.exists()
    alone = prune(jobs, "uav1", JobFilesPolicy(budget_bytes=1), now_s=2000.0)
    assert alone == [mine[3]] and mine[4].exists()  # the job just written always stays


def test_jobs_older_than_the_age_limit_go_whatever_the_budget(tmp_path: Path) -> None:
    jobs = tmp_path / "jobs"
    old = _job_dir(jobs, "j1-uav1-1", 10, 0.0)
    new = _job_dir(jobs, "j2-uav1-1", 10, 7000.0)
    policy = JobFilesPolicy(budget_bytes=10**9, max_age_s=3600.0)
    assert prune(jobs, "uav1", policy, now_s=7200.0) == [old] and new.exists()


def test_the_show_budget_is_shared_by_its_vehicles() -> None:
    show = load_show(SHOWS / "airshow-2014.yaml")
    storage = show.storage.model_copy(update={"job_files_budget_mb": 400.0})
    policy = JobFilesPolicy.of(show.model_copy(update={"storage": storage}))
    assert policy.compact and policy.budget_bytes == 100_000_000 and policy.max_age_s is None


@given(
    st.lists(st.floats(0.0, 0.05), min_size=1, max_size=300),
    st.floats(1.0, 100.0),
)
def test_decimation_keeps_the_ends_and_no_two_samples_closer_than_the_rate(
    steps_s: list[float], rate_hz: float
) -> None:
    t_s = np.cumsum(steps_s)
    keep = decimated(t_s, rate_hz)
    assert keep[0] == 0 and keep[-1] == len(t_s) - 1 and np.all(np.diff(keep) > 0)
    slots = np.floor((t_s[keep] - t_s[0]) * rate_hz + 1e-9)
    assert np.all(np.diff(slots[:-1]) >= 1)  # one sample per 1/rate slot (the last is extra)


def test_only_an_attempt_flown_to_its_end_counts_as_written_whole(tmp_path: Path) -> None:
    def folder(name: str, text: str | None) -> Path:
        path = tmp_path / name
        path.mkdir()
        if text is not None:
            (path / "metrics.json").write_text(text, encoding="utf-8")
        return path

    assert written_whole(folder("whole", '{"abort_reason": null, "metrics": {}}'))
    assert not written_whole(folder("cancelled", '{"abort_reason": "cancelled"}'))
    assert not written_whole(folder("deviation", '{"abort_reason": "deviation"}'))
    assert not written_whole(folder("being-written", None))
    assert not written_whole(folder("torn", '{"abort_reason": nul'))

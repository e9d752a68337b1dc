"""The README's SITL flows, end to end, as a new user runs them (``pytest -m sitl``):
``scripts/sitl/start.py SHOW`` until every autopilot is ready, ``skyquill up --headless SHOW``,
``skyquill submit SHOW --text X``, and the characters written (``done``: within the show's
bounds) by every vehicle of the show, paced to its own tracking (benchmarks/sitl_show.py).

Skipped, with the reason, when the autopilot's binary is not named ($SKYQUILL_ARDUCOPTER_SITL,
$SKYQUILL_PX4_SITL; README "Real autopilot SITL").
"""

from __future__ import annotations

import os
from pathlib import Path
from types import ModuleType

import pytest
from module_by_path import load_module

from showfile import load_show

ROOT = Path(__file__).resolve().parents[1]
SHOWS = {"ardupilot": "sitl-ardupilot.yaml", "px4": "sitl-px4.yaml"}
VARIABLES = {"ardupilot": "SKYQUILL_ARDUCOPTER_SITL", "px4": "SKYQUILL_PX4_SITL"}


def sitl_show() -> ModuleType:
    return load_module("sitl_show", ROOT / "benchmarks/sitl_show.py")


@pytest.mark.sitl
@pytest.mark.slow
@pytest.mark.timeout(1200)
@pytest.mark.parametrize("kind", ["ardupilot", "px4"])
def test_the_readme_flow_writes_on_every_vehicle(kind: str, tmp_path: Path) -> None:
    if not os.environ.get(VARIABLES[kind]):
        pytest.skip(f'{VARIABLES[kind]} not set: path of the {kind} SITL binary (README, "Real '
                    'autopilot SITL")')  # fmt: skip
    module = sitl_show()
    show = ROOT / "shows" / SHOWS[kind]
    with module.running(show, tmp_path) as run:
        vehicles = run.status()["vehicles"]
        ids = [run.submit(text) for text in ("火", "R")[: len(vehicles)]]
        jobs = [j for j in run.wait_jobs(len(ids), 900.0) if j["job_id"] in ids]
        events = run.events()
    for job in jobs:
        print(f"{kind} {job['vehicle_id']} {job['label']} {job['state']} {job.get('metrics')}")
    assert sorted(j["vehicle_id"] for j in jobs) == sorted(v["vehicle_id"] for v in vehicles)
    assert [j["state"] for j in jobs] == ["done"] * len(ids), [j.get("error") for j in jobs]
    first_stretch = load_show(show).planning.pace_first_stretch
    for job in jobs:  # the first job of a vehicle: the show's pace before any identification
        assert job["metrics"]["extra"]["pace_stretch"] == first_stretch
    faults = [e for e in events if e["kind"] in ("vehicle_fault", "geofence", "not_settled")]
    assert not faults, faults

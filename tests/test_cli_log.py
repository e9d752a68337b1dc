"""``skyquill log``: the whole event log from the show's database, as text, JSON Lines or CSV."""

from __future__ import annotations

import csv
import io
import json
import time
from pathlib import Path

import pytest
from test_orchestrator_service import make_show

from bus.messages import Event
from cli.cmd_log import since_s
from cli.main import main as skyquill
from orchestrator.store import JobStore


def _events(now_s: float) -> list[Event]:
    return [
        Event(time_s=now_s - 7200.0, level="info", kind="job_submitted", message="永 from k-1"),
        Event(
            time_s=now_s - 600.0,
            level="alert",
            kind="vehicle_lost",
            message="uav2 lost",
            vehicle_id="uav2",
            job_id="j1",
        ),
        Event(time_s=now_s - 60.0, level="info", kind="operator", message="=HYPERLINK(x)\x1b[2J"),
    ]


@pytest.fixture
def show_path(tmp_path: Path) -> Path:
    path, show = make_show(tmp_path, "logged", "tcp/127.0.0.1:1")
    with JobStore(show.database_path) as store:
        store.save([], _events(time.time()))  # times from now: the suite may run long
    return path


def test_the_log_prints_every_event_in_order_and_no_terminal_code(
    show_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert skyquill(["log", str(show_path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == 3 and "永 from k-1" in lines[0]
    assert "vehicle_lost" in lines[1] and "uav2 j1 uav2 lost" in lines[1]
    assert "\x1b" not in lines[2] and "␛[2J" in lines[2]


def test_json_lines_and_since(show_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert skyquill(["log", str(show_path), "--json", "--since", "15m"]) == 0
    rows = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [r["kind"] for r in rows] == ["vehicle_lost", "operator"]
    assert rows[0]["time"].endswith("Z") and rows[0]["time_s"] == pytest.approx(
        time.time() - 600.0, abs=60.0
    )
    assert rows[1]["message"] == "=HYPERLINK(x)\x1b[2J"  # data, exactly as stored


def test_csv_cells_never_run_as_formulas(
    show_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert skyquill(["log", str(show_path), "--csv"]) == 0
    rows = list(csv.DictReader(io.StringIO(capsys.readouterr().out)))
    assert [r["kind"] for r in rows] == ["job_submitted", "vehicle_lost", "operator"]
    assert rows[2]["message"].startswith("'=HYPERLINK")


def test_the_log_reads_without_writing_and_bad_input_is_one_line(
    tmp_path: Path, show_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    database = tmp_path / "show.sqlite3"
    before = database.stat().st_mtime_ns, database.read_bytes()
    assert skyquill(["log", str(show_path), "--since", "1d"]) == 0
    assert (database.stat().st_mtime_ns, database.read_bytes()) == before
    capsys.readouterr()
    assert skyquill(["log", str(show_path), "--since", "yesterday"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--since 'yesterday'" in err and "15m" in err
    database.unlink()
    assert skyquill(["log", str(show_path)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no show database here" in err


def test_since_takes_durations_and_moments() -> None:
    assert since_s("90s", 1000.0) == 910.0 and since_s("2h", 10_000.0) == 2800.0
    assert since_s("2026-11-29T14:00+00:00", 0.0) == 1795960800.0

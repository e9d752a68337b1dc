"""One voice across commands (:mod:`cli.summary`): significant digits with units, a verdict in
words, the character itself; and the rough edges a newcomer met: ``status`` with no show
running, ``up``'s addresses, the demo's labelled table, a glyph without a frame laid out in its
box."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from bus.messages import JobMetrics, JobState, JobStateName
from bus.session import BusSettings, free_tcp_endpoint, open_session
from cli import cmd_demo, cmd_status, cmd_up
from cli.main import main
from cli.summary import feasible, length, limits_line, plan_headline, printable, sig
from cli.viewer import UpOutput
from showfile import load_show

SHOWS = Path(__file__).resolve().parents[1] / "shows"


@pytest.mark.parametrize(
    ("value", "digits", "shown"),
    [
        (20.43, 3, "20.4"),
        (0.002134, 3, "0.00213"),
        (9.996, 3, "10"),  # rounds up a decade: still three digits, no 10.00
        (0.30, 2, "0.3"),
        (1234.5, 3, "1230"),  # never 1.23e+03
        (-0.5, 3, "-0.5"),
        (0.0, 3, "0"),
        (46.663661724553066, 3, "46.7"),  # what ``fly`` printed as 16 digits
        (float("nan"), 3, "-"),
        (None, 3, "-"),
    ],
)
def test_numbers_are_shown_to_a_few_significant_digits(
    value: float | None, digits: int, shown: str
) -> None:
    assert sig(value, digits) == shown


def test_significant_digits_hold_across_magnitudes() -> None:
    for exponent in range(-6, 6):
        for mantissa in (1.0, 1.2345, 9.87654, 5.5):
            value = mantissa * 10.0**exponent
            text = sig(value, 3)
            assert "e" not in text
            assert math.isclose(float(text), value, rel_tol=5e-3)


def test_lengths_choose_millimetres_below_ten_centimetres() -> None:
    assert length(0.00213) == "2.13 mm"
    assert length(0.95) == "0.95 m"
    assert length(None) == "not measured"


def test_a_kind_plan_says_feasible_no_when_a_peak_passes_its_limit() -> None:
    within = {"peak_speed_mps": 0.19, "v_max_mps": 0.2, "peak_accel_mps2": [0.2, 0.1],
              "accel_max_mps2": [0.25, 0.15], "n_spans": 206}  # fmt: skip
    assert feasible(within)
    assert feasible({**within, "peak_speed_mps": 0.2002})  # round-off: 0.1 %
    assert not feasible({**within, "peak_speed_mps": 0.23})
    assert not feasible({**within, "peak_accel_mps2": [0.2, 0.16]})
    assert feasible({**within, "peak_speed_mps": 9.0, "feasible": True})  # the kind's own word
    assert limits_line(within) == "speed 0.19 of 0.2 m/s; accel 0.2, 0.1 of 0.25, 0.15 m/s^2"
    head = plan_headline("永", "omni-wheel", (0.9, 0.853), 41.14, 5, feasible(within))
    assert head == "永 for omni-wheel: 0.9 x 0.853 m, 41.1 s to write, 5 strokes; feasible: yes"


def test_a_label_from_anyone_cannot_drive_the_terminal() -> None:
    assert printable("永\x1b[31mred\u202e") == "永U+001B[31mredU+202E"


def test_a_glyph_without_a_frame_fits_its_box(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """一 (one flat stroke) is as wide as the box less its margins, not metres wide."""
    assert main(["plan", "--text", "一", "--json"]) == 0
    width_m, height_m = json.loads(capsys.readouterr().out)["ink_size_m"]
    assert width_m == pytest.approx(0.9) and height_m < 0.9
    assert main(["plan", "--kind", "omni-wheel", "--text", "一", "--width", "0.5", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["ink_size_m"][0] == pytest.approx(0.4)
    with pytest.raises(SystemExit) as exited:
        main(["plan", "--text", "一", "--height", "0"])
    assert exited.value.code == 2
    assert "argument --height: must be above 0 m" in capsys.readouterr().err


def test_plan_for_another_kind_prints_the_character_and_its_verdict(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["plan", "--kind", "omni-wheel", "--text", "永"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("永 for omni-wheel: 0.9 x 0.853 m, ")
    assert lines[0].endswith(" s to write, 5 strokes; feasible: yes")
    assert lines[1].startswith("  peak speed ") and "m/s^2" in lines[1]
    assert len(lines) == 2  # solver internals: --json


def _show_without_keys(tmp_path: Path, endpoint: str) -> Path:
    """``shows/solo.yaml`` on ``endpoint``, open (no keys to make), storage under tmp."""
    text = (SHOWS / "solo.yaml").read_text(encoding="utf-8")
    text = text.replace("tcp/127.0.0.1:7448", endpoint).replace("mode: mtls", "mode: none")
    text = text.replace(
        "multicast_scouting: false", "multicast_scouting: false\n  open_timeout_s: 1"
    )
    text = text.replace("../out/solo", str(tmp_path / "out"))
    path = tmp_path / "solo.yaml"
    path.write_text(text, encoding="utf-8")
    return path


def test_status_with_no_show_running_names_the_endpoint_and_the_way_out(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    endpoint = free_tcp_endpoint()
    path = _show_without_keys(tmp_path, endpoint)
    assert main(["status", str(path), "--timeout", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err == (
        f"skyquill status: no show running at {endpoint}: start it with `skyquill up {path}`"
    )


def test_status_with_a_router_but_no_orchestrator_says_which_is_missing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    endpoint = free_tcp_endpoint()
    path = _show_without_keys(tmp_path, endpoint)
    with open_session(BusSettings(router_listen=[endpoint], connect=[endpoint]), role="router"):
        assert main(["status", str(path), "--timeout", "0.5"]) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert f"the router at {endpoint} answers, but no orchestrator of show solo" in err
    assert f"`skyquill up {path}`" in err and ".rs:" not in err


def test_status_names_a_vehicles_job_once() -> None:
    assert cmd_status.vehicle_note("jc37ed52cdaec", "job jc37ed52cdaec") == ""
    assert cmd_status.vehicle_note("j1", "job j1 written") == "written"
    assert cmd_status.vehicle_note(None, "battery low") == "battery low"


def test_up_prints_the_kiosks_address_and_the_consoles_command(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    show = load_show(SHOWS / "airshow-2014.yaml")
    url = cmd_up.kiosk_url(show)
    assert url == f"http://127.0.0.1:{show.kiosk.port}/"
    output = UpOutput(tmp_path / "up.log")
    cmd_up._announce_addresses(output, Path("shows/airshow-2014.yaml"), url, tui=False)
    output.close()
    err = capsys.readouterr().err
    assert f"skyquill up: kiosk: {url}" in err
    assert "skyquill up: console: `skyquill tui shows/airshow-2014.yaml`" in err
    wildcard = show.model_copy(
        update={"kiosk": show.kiosk.model_copy(update={"host": "0.0.0.0", "port": 9000})}
    )
    assert cmd_up.kiosk_url(wildcard) == "http://127.0.0.1:9000/"


def _job(job_id: str, state: JobStateName, metrics: JobMetrics | None) -> JobState:
    return JobState(
        job_id=job_id,
        state=state,
        label="永",
        kind="text",
        client_id="demo",
        created_at_s=0.0,
        updated_at_s=0.0,
        vehicle_id="uav1",
        metrics=metrics,
    )


def test_the_demo_table_labels_simulated_time_and_claims_no_ink_for_a_failed_job() -> None:
    done = JobMetrics(rmse_pen_down_m=0.0021, rmse_m=0.0035, max_error_m=0.01, iou=0.88,
                      duration_s=20.43)  # fmt: skip
    aborted = JobMetrics(rmse_pen_down_m=0.0, rmse_m=0.06, max_error_m=0.07, iou=1.0,
                         duration_s=0.31)  # fmt: skip
    table = cmd_demo._table(["永", "光"], [_job("j1", "done", done), _job("j2", "failed", aborted)])
    header, _, first, second = table.splitlines()
    assert header.split() == ["text", "job", "vehicle", "state", "pen-down", "RMSE", "RMSE",
                              "ink", "IoU", "sim", "time"]  # fmt: skip
    assert "2.1 mm" in first and "0.88" in first and "20.4 s" in first
    assert second.split()[-3] == "0.00"  # a failed job wrote nothing that counts
    assert "1.00" not in second


def test_the_demo_lists_the_files_its_jobs_really_hold(tmp_path: Path) -> None:
    for name in ("metrics.json", "flight.npz", "report.png"):
        (tmp_path / "j1-uav1-1").mkdir(exist_ok=True)
        (tmp_path / "j1-uav1-1" / name).write_bytes(b"x")
    assert cmd_demo.job_files(tmp_path) == "metrics.json, flight.npz, report.png"
    assert cmd_demo.job_files(tmp_path / "none") == "none written"

"""``skyquill fly``: plans, flies, writes metrics.json and report.png."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cli.main import main

DATA = Path(__file__).parent / "data"


def test_fly_writes_metrics_and_report(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "report"
    status = main(
        ["fly", "--strokes", str(DATA / "l_tick_m_up.json"), "--wind", "1", "--seed", "3",
         "--height", "0.5", "--report", str(out), "--json"]
    )  # fmt: skip
    assert status == 0
    metrics = json.loads((out / "metrics.json").read_text(encoding="utf-8"))
    for key in ("rmse_pen_down_m", "rmse_m", "max_error_m", "iou", "sim_time_s", "wall_time_s"):
        assert isinstance(metrics[key], float)
    assert metrics["seed"] == 3 and metrics["wind_mps"] == 1.0
    assert metrics["gains"]["name"] == "default"
    assert 0.0 < metrics["rmse_pen_down_m"] < 0.01
    assert metrics["iou"] > 0.7
    png = (out / "report.png").read_bytes()
    assert png.startswith(b"\x89PNG") and len(png) > 50_000
    assert json.loads(capsys.readouterr().out.strip().splitlines()[-1])["iou"] == metrics["iou"]


def test_fly_and_plan_lay_a_character_out_alike(capsys: pytest.CaptureFixture[str]) -> None:
    """The same defaults: the planned time ``fly`` reports is the one ``plan`` prints, to the
    precision of the interior point: ``plan`` solves its QPs on PIQP's dense interface, ``fly``
    on the sparse one, and their solutions of the time law's QP (planner.time_law) differ by
    about 1e-6, the durations by about 1e-5 (another default, as a height or a limit, moves them
    by far more)."""
    assert main(["plan", "--text", "I", "--json"]) == 0
    planned = json.loads(capsys.readouterr().out)
    assert main(["fly", "--text", "I", "--json"]) == 0
    flown = json.loads(capsys.readouterr().out)
    assert flown["planned_duration_s"] == pytest.approx(planned["duration_s"], rel=1e-4)
    assert flown["within_bounds"] is True and 0.3 < flown["iou"] <= 1.0
    assert main(["fly", "--text", "I"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("I by quadrotor-brush: written, within bounds: ink IoU 0.")
    assert "pen-down RMSE" in lines[2] and " mm" in lines[2]


def test_fly_reports_a_bad_strokes_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text('{"strokes": "nope"}', encoding="utf-8")
    assert main(["fly", "--strokes", str(bad)]) == 2
    assert "skyquill fly:" in capsys.readouterr().err


def test_fly_in_a_gale_aborts_on_deviation_and_exits_non_zero(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "gale"
    status = main(["fly", "--strokes", str(DATA / "l_tick_m_up.json"), "--wind", "10",
                   "--height", "0.5", "--report", str(out)])  # fmt: skip
    assert status == 1
    captured = capsys.readouterr()
    err = captured.err
    assert "deviation abort of vehicle 0" in err and "above the bound 0.150 m for 0.30 s" in err
    metrics = json.loads((out / "metrics.json").read_text(encoding="utf-8"))
    assert metrics["within_bounds"] is False and "deviation" in metrics["aborted"]
    assert metrics["sim_time_s"] < 1.0  # stopped at once, not flown to the end
    # it wrote nothing, and claims nothing: IoU 0 (not 1.0), no pen-down RMSE (not 0.0)
    assert metrics["wrote_ink"] is False
    assert metrics["iou"] == 0.0 and metrics["rmse_pen_down_m"] is None
    unmeasured = [k for k in metrics if k.startswith("ink_") or "pen_down" in k]
    assert unmeasured == ["rmse_pen_down_m"]  # the kind's pen-down and ink figures left out
    head = captured.out.splitlines()[0]
    assert "ABORTED at 0.3" in head and "nothing written: ink IoU 0" in head
    assert "pen-down RMSE not measured" in captured.out


@pytest.mark.parametrize(
    ("flags", "named"),
    [
        (["--wind", "50"], "--wind 50 m/s: above 15.3 m/s"),
        (["--wind", "-1"], "argument --wind: must be at least 0 m/s"),
        (["--height", "0"], "argument --height: must be above 0 m"),
        (["--iou-min", "1.5"], "argument --iou-min: must be at least 0 and at most 1"),
        (["--seed", "-1"], "--seed must be 0 or more"),
        (["--margin", "0.6"], "<text>: --margin: margins of 0.6 m leave no room"),
    ],
)
def test_fly_refuses_a_flag_out_of_range_naming_it(
    flags: list[str], named: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exited:  # argparse's own refusals exit
        raise SystemExit(main(["fly", "--text", "I", *flags]))
    assert exited.value.code == 2
    err = capsys.readouterr().err
    assert named in err and "Traceback" not in err and "width_m" not in err


def test_fly_below_its_ink_bound_exits_non_zero(capsys: pytest.CaptureFixture[str]) -> None:
    status = main(["fly", "--strokes", str(DATA / "l_tick_m_up.json"), "--height", "0.5",
                   "--iou-min", "0.99"])  # fmt: skip
    assert status == 1
    assert "writing out of bounds: ink IoU" in capsys.readouterr().err


@pytest.mark.slow
def test_fly_another_kind_through_its_room(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "floor"
    status = main(["fly", "--kind", "omni-wheel", "--strokes", str(DATA / "l_tick_m_up.json"),
                   "--height", "1.0", "--report", str(out)])  # fmt: skip
    assert status == 0, capsys.readouterr().err
    metrics = json.loads((out / "metrics.json").read_text(encoding="utf-8"))
    assert metrics["kind"] == "omni-wheel" and metrics["within_bounds"] is True
    assert 0.0 < metrics["rmse_pen_down_m"] < 0.005 and metrics["iou"] > 0.8
    assert (out / "report.png").read_bytes().startswith(b"\x89PNG")


def test_a_brush_option_is_refused_for_another_kind(capsys: pytest.CaptureFixture[str]) -> None:
    status = main(["fly", "--kind", "omni-wheel", "--text", "I", "--wind", "3"])
    assert status == 2
    assert "--wind is an option of quadrotor-brush, not of omni-wheel" in capsys.readouterr().err


@pytest.mark.slow
def test_fly_the_wall_hexarotor_reports_table_one(tmp_path: Path) -> None:
    out = tmp_path / "wall"
    status = main(["fly", "--kind", "hexarotor-sponge", "--text", "I", "--height", "0.3",
                   "--report", str(out)])  # fmt: skip
    assert status == 0
    metrics = json.loads((out / "metrics.json").read_text(encoding="utf-8"))
    assert metrics["rmse_ee_m"] < 0.015 and metrics["force_rmse_n"] < 0.6
    assert metrics["rmse_base_m"] > 0.0 and metrics["iou"] > 0.6
    assert metrics["feasibility"]["ipopt_iterations"]

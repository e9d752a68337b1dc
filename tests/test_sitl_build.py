"""scripts/sitl/build.py and source_edits.py: the edits made to an autopilot checkout before it is
built (loopback binds, PX4 board options, SIH's vibration parameter), checked on files that hold
the texts of the releases they were written for; checkouts refused for their submodules; the build
steps' failures, on a fake ``./waf``. The builds themselves are run by hand (README)."""

from __future__ import annotations

import importlib.util
import re
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

SITL_SCRIPTS = Path(__file__).resolve().parents[1] / "scripts" / "sitl"
STOCK_ARMED_NOISE = {"accel": (0.5, 1.7, 1.4), "gyro": (0.14, 0.07, 0.03)}
"""SIH 1.16's armed IMU noise std (m/s^2, rad/s), x / y / z."""
STOCK_DISARMED_NOISE = {"accel": (0.1, 0.1, 0.1), "gyro": (0.01, 0.01, 0.01)}


def by_path(name: str) -> ModuleType:
    module = sys.modules.get(name)
    if module is None:
        spec = importlib.util.spec_from_file_location(name, SITL_SCRIPTS / f"{name}.py")
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def build() -> ModuleType:
    return by_path("build")  # imports source_edits beside it


@pytest.fixture(scope="module")
def edits() -> ModuleType:
    return by_path("source_edits")


def checkout(root: Path, recipe_edits: tuple[Any, ...]) -> Path:
    """A checkout whose files hold each edit's text between other lines, as the release does."""
    for edit in recipe_edits:
        path = root / edit.path
        path.parent.mkdir(parents=True, exist_ok=True)
        old = path.read_text() if path.exists() else "// head\n"
        path.write_text(old + edit.before + "// between\n")
    return root


@pytest.mark.parametrize("autopilot", ["ardupilot", "px4"])
def test_every_edit_applies_once_then_is_found_present(
    build: ModuleType, tmp_path: Path, autopilot: str
) -> None:
    recipe = build.RECIPES[autopilot]
    root = checkout(tmp_path, recipe.edits)
    first = build.apply_edits(root, recipe.edits)
    assert [outcome for _, outcome in first] == ["applied"] * len(recipe.edits)
    texts = {p: p.read_text() for p in root.rglob("*") if p.is_file()}
    for edit in recipe.edits:
        assert edit.after in texts[root / edit.path]
    again = build.apply_edits(root, recipe.edits)
    assert [outcome for _, outcome in again] == ["present"] * len(recipe.edits)
    assert texts == {p: p.read_text() for p in root.rglob("*") if p.is_file()}


@pytest.mark.parametrize("autopilot", ["ardupilot", "px4"])
def test_no_listener_is_left_on_every_interface(build: ModuleType, autopilot: str) -> None:
    recipe = build.RECIPES[autopilot]
    binds = [e for e in recipe.edits if "INADDR" in e.before + e.after]
    assert binds, "the recipe binds nothing to loopback"
    for edit in binds:
        assert "INADDR_ANY" not in edit.after and "INADDR_LOOPBACK" in edit.after


def test_a_checkout_of_another_release_is_named_and_left_untouched(
    build: ModuleType, edits: ModuleType, tmp_path: Path
) -> None:
    recipe = build.RECIPES["px4"]
    root = checkout(tmp_path, recipe.edits)
    sih = root / recipe.edits[-1].path
    sih.write_text(sih.read_text().replace("noiseGauss3f(0.5f", "noiseGauss3f(0.6f"))
    before = {p: p.read_text() for p in root.rglob("*") if p.is_file()}
    with pytest.raises(edits.EditError, match=r"sih\.cpp: expected exactly one .*found 0"):
        build.apply_edits(root, recipe.edits)
    assert before == {p: p.read_text() for p in root.rglob("*") if p.is_file()}


def test_sih_vibration_spans_the_disarmed_level_to_sih_own(edits: ModuleType) -> None:
    """The scaled noise is the disarmed level at SIH_IMU_VIB 0 and SIH's stock level at 1."""
    (sih,) = [e for e in edits.PX4_EDITS if e.path.endswith("sih.cpp")]
    for sensor in ("accel", "gyro"):
        stock = re.search(rf"{sensor}_noise = noiseGauss3f\(([^)]*)\)", sih.before)
        scaled = re.search(rf"{sensor}_noise = noiseGauss3f\(([^;]*)\);", sih.after)
        assert stock and scaled
        assert [float(v.rstrip("f")) for v in stock.group(1).split(",")] == pytest.approx(
            STOCK_ARMED_NOISE[sensor]
        )
        terms = [
            re.fullmatch(r"\s*([\d.]+)f \+ vib \* ([\d.]+)f\s*", t)
            for t in scaled.group(1).split(",")
        ]
        assert all(terms)
        at_zero = [float(t.group(1)) for t in terms if t]
        at_one = [float(t.group(1)) + float(t.group(2)) for t in terms if t]
        assert at_zero == pytest.approx(STOCK_DISARMED_NOISE[sensor])
        assert at_one == pytest.approx(STOCK_ARMED_NOISE[sensor])
    (params,) = [e for e in edits.PX4_EDITS if e.path.endswith("sih_params.c")]
    assert "PARAM_DEFINE_FLOAT(SIH_IMU_VIB, 1.0f);" in params.after  # stock unless set


def test_a_checkout_without_its_submodules_is_refused_naming_them(
    build: ModuleType, tmp_path: Path
) -> None:
    recipe = build.RECIPES["px4"]
    (tmp_path / recipe.marker).parent.mkdir(parents=True)
    (tmp_path / recipe.marker).write_text("")
    for sub in recipe.submodules[1:]:
        (tmp_path / sub).mkdir(parents=True)
        (tmp_path / sub / "CMakeLists.txt").write_text("")
    with pytest.raises(build.BuildError, match=r"submodules missing: src/modules/mavlink/mavlink "):
        build.check_checkout("px4", tmp_path)
    with pytest.raises(build.BuildError, match="not a ardupilot checkout"):
        build.check_checkout("ardupilot", tmp_path)


def test_the_edits_only_run_prints_each_edit_and_exits_two_on_a_bad_checkout(
    build: ModuleType, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    recipe = build.RECIPES["ardupilot"]
    root = checkout(tmp_path, recipe.edits)
    (root / recipe.marker).parent.mkdir(parents=True, exist_ok=True)
    (root / recipe.marker).write_text("")
    for sub in recipe.submodules:
        (root / sub).mkdir(parents=True, exist_ok=True)
        (root / sub / "x").write_text("")
    assert build.main(["ardupilot", str(root), "--edits-only"]) == 0
    assert capsys.readouterr().out.count(" applied: ") == len(recipe.edits)
    assert build.main(["px4", str(root), "--edits-only"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("build.py: ") and err.count("\n") == 1 and "not a px4 checkout" in err


def test_a_submodule_holding_only_its_git_link_is_refused_with_the_command_that_fills_it(
    build: ModuleType, tmp_path: Path
) -> None:
    recipe = build.RECIPES["ardupilot"]
    (tmp_path / recipe.marker).parent.mkdir(parents=True)
    (tmp_path / recipe.marker).write_text("")
    for sub in recipe.submodules:
        (tmp_path / sub).mkdir(parents=True, exist_ok=True)
        (tmp_path / sub / "wscript").write_text("")
    (tmp_path / "modules/waf/wscript").unlink()  # registered by git, never checked out
    (tmp_path / "modules/waf/.git").write_text("gitdir: ../../.git/modules/modules/waf\n")
    command = f"git -C {tmp_path} submodule update --init --recursive modules/waf)"
    with pytest.raises(build.BuildError, match=r"submodules missing: modules/waf \(") as refused:
        build.check_checkout("ardupilot", tmp_path)
    assert str(refused.value).endswith(command)
    (tmp_path / "modules/waf/waf-light").write_text("")
    build.check_checkout("ardupilot", tmp_path)


def fake_waf(root: Path, body: str) -> Path:
    """An ArduPilot checkout whose ``./waf`` is a shell script that logs its arguments to
    ``waf.log`` and then runs ``body``."""
    waf = root / "waf"
    waf.write_text(f'#!/bin/sh\necho "$@" >> "$(dirname "$0")/waf.log"\n{body}\n')
    waf.chmod(0o755)
    return root / "waf.log"


def test_a_step_that_says_a_submodule_is_missing_stops_the_build_although_it_exits_0(
    build: ModuleType, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """ArduPilot's ./waf without modules/waf/waf-light: its two lines, then exit 0."""
    log = fake_waf(tmp_path, "echo 'Missing waf submodule. Trying to get it'\n"
                             "echo 'Submodules OK, try running again'\nexit 0")  # fmt: skip
    with pytest.raises(build.BuildError) as failed:
        build.build("ardupilot", tmp_path, tmp_path)
    message = str(failed.value)
    assert message == (
        "./waf configure --board sitl --no-submodule-update failed "
        "(exit 0, but it said: Missing waf submodule. Trying to get it)"
    )
    assert log.read_text().splitlines() == ["configure --board sitl --no-submodule-update"]
    out = capsys.readouterr().out  # shown to the user as well as read
    assert "Missing waf submodule" in out and "try running again" in out


def test_a_step_that_exits_non_zero_stops_the_build_and_one_that_succeeds_builds(
    build: ModuleType, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = fake_waf(tmp_path, "echo 'waf: no such board' >&2\nexit 1")
    with pytest.raises(build.BuildError, match=r"^\./waf configure .* failed \(exit 1\)"):
        build.build("ardupilot", tmp_path, tmp_path)
    assert len(log.read_text().splitlines()) == 1
    assert "waf: no such board" in capsys.readouterr().out
    log.unlink()
    binary = tmp_path / build.RECIPES["ardupilot"].binary
    fake_waf(tmp_path, f"echo \"'configure' finished successfully\"\n"
                       f"mkdir -p {binary.parent} && touch {binary}")  # fmt: skip
    assert build.build("ardupilot", tmp_path, tmp_path) == binary
    assert log.read_text().splitlines() == [
        "configure --board sitl --no-submodule-update",
        "copter --no-submodule-update",
    ]

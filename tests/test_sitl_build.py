"""scripts/sitl/build.py and source_edits.py: the edits made to an autopilot checkout before it is
built (loopback binds, PX4 board options, SIH's vibration parameter), checked on files that hold
the texts of the releases they were written for; checkouts refused for their submodules; the build
steps' failures, on a fake ``./waf``. The builds themselves are run by hand (README)."""

from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest
from module_by_path import load_module

SITL_SCRIPTS = Path(__file__).resolve().parents[1] / "scripts" / "sitl"
STOCK_ARMED_NOISE = {"accel": (0.5, 1.7, 1.4), "gyro": (0.14, 0.07, 0.03)}
"""SIH 1.16's armed IMU noise std (m/s^2, rad/s), x / y / z."""
STOCK_DISARMED_NOISE = {"accel": (0.1, 0.1, 0.1), "gyro": (0.01, 0.01, 0.01)}


def by_path(name: str) -> ModuleType:
    return load_module(name, SITL_SCRIPTS / f"{name}.py")


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
    binds = [e for e in recipe.edits if "loopback only" in e.after]
    assert binds, "the recipe binds nothing to loopback"
    for edit in binds:
        assert "INADDR_ANY" not in edit.after and '"0.0.0.0"' not in edit.after
        assert "INADDR_LOOPBACK" in edit.after or '"127.0.0.1"' in edit.after


def test_a_checkout_of_another_release_is_named_and_left_untouched(
    build: ModuleType, edits: ModuleType, tmp_path: Path
) -> None:
    recipe = build.RECIPES["px4"]
    root = checkout(tmp_path, recipe.edits)
    (sih_edit,) = [e for e in recipe.edits if e.path.endswith("sih.cpp")]
    sih = root / sih_edit.path
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
    mavlink = "src/modules/mavlink/mavlink"  # with pymavlink inside it, a submodule of its own
    for sub in recipe.submodules:
        if not sub.startswith(mavlink):
            (tmp_path / sub).mkdir(parents=True)
            (tmp_path / sub / "CMakeLists.txt").write_text("")
    expected = f"submodules missing: {mavlink}, {mavlink}/pymavlink "
    with pytest.raises(build.BuildError, match=expected):
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


PX4_STARTUP_RUNS = (
    ("MAV_SYS_ID", 'param() { echo "param $*"; }\n', ""),
    ("udp_offboard_port_remote", "udp_offboard_port_remote=$((14540+px4_instance))\n",
     'echo "remote $udp_offboard_port_remote"\n'),
    ("udp_gcs_port_local", 'mavlink() { echo "mavlink $*"; }\nudp_gcs_port_local=18573\n', ""),
)  # fmt: skip
"""Per PX4 startup edit (found by a word of its text): what it needs before it to run alone in
/bin/sh, and what to print after it."""
PX4_PORT_ENV = {
    "PX4_SYS_ID": "42",
    "PX4_OFFBOARD_REMOTE_PORT": "47650",
    "PX4_GCS_REMOTE_PORT": "14563",
}


def run_sh(script: str, env: dict[str, str]) -> str:
    """stdout of ``script`` run by /bin/sh (PX4 SITL runs its startup scripts so)."""
    done = subprocess.run(["/bin/sh", "-c", script], env={"PATH": "/usr/bin:/bin", **env},
                          capture_output=True, text=True, check=True)  # fmt: skip
    return done.stdout


@pytest.mark.parametrize("px4_instance", [3, 12])
def test_px4_startup_takes_its_system_id_and_ports_from_the_environment_only_when_set(
    edits: ModuleType, px4_instance: int
) -> None:
    startup = [e for e in edits.PX4_EDITS if "init.d-posix" in e.path]
    assert len(startup) == len(PX4_STARTUP_RUNS)
    outputs = []
    for word, prelude, show in PX4_STARTUP_RUNS:
        (edit,) = [e for e in startup if word in e.before]
        head = f"px4_instance={px4_instance}\n{prelude}"
        stock = run_sh(head + edit.before + show, {})
        assert run_sh(head + edit.after + show, {}) == stock  # unset: as shipped
        outputs.append((stock, run_sh(head + edit.after + show, PX4_PORT_ENV)))
    (sys_id, sys_id_set), (remote, remote_set), (gcs, gcs_set) = outputs
    assert sys_id == f"param set MAV_SYS_ID {px4_instance + 1}\n"
    assert sys_id_set == "param set MAV_SYS_ID 42\n"
    assert remote == f"remote {14540 + px4_instance if px4_instance <= 9 else 14549}\n"
    assert remote_set == "remote 47650\n"
    assert gcs == "mavlink start -x -u 18573 -r 4000000 -f\n"  # PX4 sends to 14550
    assert gcs_set == "mavlink start -x -u 18573 -r 4000000 -f -o 14563\n"


def px4_checkout() -> Path | None:
    """The PX4 checkout $SKYQUILL_PX4_SITL was built from, when it is a git checkout."""
    binary = os.environ.get("SKYQUILL_PX4_SITL")
    if not binary:
        return None
    root = Path(binary).resolve().parents[3]  # build/px4_sitl_default/bin/px4
    return root if (root / ".git").exists() else None


def test_the_px4_startup_edits_apply_to_the_release_files_and_run(
    edits: ModuleType, tmp_path: Path
) -> None:
    """On a copy of v1.16's own px4-rc.mavlink and rcS (as committed in the checkout): every
    link of px4-rc.mavlink starts as shipped when the variables are unset, and the offboard and
    GCS links send where they say when set."""
    root = px4_checkout()
    if root is None:
        pytest.skip("SKYQUILL_PX4_SITL not set or not built in a PX4 git checkout")
    startup = tuple(e for e in edits.PX4_EDITS if "init.d-posix" in e.path)
    for path in {e.path for e in startup}:
        stock = subprocess.run(["git", "-C", str(root), "show", f"HEAD:{path}"],
                               capture_output=True, text=True, check=True).stdout  # fmt: skip
        (tmp_path / path).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / path).write_text(stock)
    mavlink_rc = tmp_path / startup[-1].path
    stub = 'mavlink() { echo "mavlink $*"; }\npx4_instance=2\nPX4_SIMULATOR=sihsim\n'
    shipped = run_sh(stub + mavlink_rc.read_text(), {})
    assert [o for _, o in edits.apply_edits(tmp_path, startup)] == ["applied"] * 3
    assert run_sh(stub + mavlink_rc.read_text(), {}) == shipped
    ours = run_sh(stub + mavlink_rc.read_text(), PX4_PORT_ENV).splitlines()
    assert "mavlink start -x -u 18572 -r 4000000 -f -o 14563" in ours
    assert "mavlink start -x -u 14582 -r 4000000 -f -m onboard -o 47650" in ours
    rcs = (tmp_path / startup[0].path).read_text()
    (line,) = [x for x in rcs.splitlines() if x.startswith("param set MAV_SYS_ID")]
    assert rcs.index("PX4_PARAM_") < rcs.index(line)  # after the overrides, as before
    param = 'param() { echo "param $*"; }\npx4_instance=2\n'
    assert run_sh(param + line, {}) == "param set MAV_SYS_ID 3\n"
    assert run_sh(param + line, PX4_PORT_ENV) == "param set MAV_SYS_ID 42\n"

"""The README's first steps, run as a newcomer runs them on a fresh clone: every command exits 0
and prints no traceback and no warning, and writes what the README says it writes.

A fresh clone is the tree as it would be committed (tracked files and new files not ignored,
without ``out/``, caches or ``.venv``), copied to a temporary folder; the commands run there on
this checkout's ``.venv`` with that copy first on the import path (asserted), so they use the
copy's code, data and show files, never this checkout's ``out/``.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from cli.main import _discover

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
VENV_BIN = Path(sys.executable).parent
NOISE = re.compile(r"Traceback \(most recent call last\)|\b\w*Warning\b")
"""A traceback, or any warning class's name (``UserWarning: ...``, ``DeprecationWarning``)."""


def first_steps(readme: str) -> list[str]:
    """The commands of the README's "First steps" block, comments and activation left out."""
    section = readme.split("## First steps", 1)[1]
    block = section.split("```sh\n", 1)[1].split("```", 1)[0]
    commands = []
    for line in block.splitlines():
        command = line.split("  #", 1)[0].strip()
        if command and not command.startswith(". "):
            commands.append(command)
    return commands


def table_commands(readme: str) -> set[str]:
    """The subcommands named in the first column of the README's table of commands."""
    table = readme.split("## What you can run", 1)[1].lstrip("\n").split("\n\n", 1)[0]
    rows = [line.split(" | ", 1)[0] for line in table.splitlines() if line.startswith("| `")]
    return {name for row in rows for name in re.findall(r"`skyquill ([a-z-]+)", row)}


def fresh_clone(into: Path) -> Path:
    """The files a commit of the working tree would hold, copied under ``into``."""
    listed = subprocess.run(
        ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
        cwd=ROOT,
        capture_output=True,
        check=True,
    ).stdout.decode()
    clone = into / "skyquill"
    for name in filter(None, listed.split("\0")):
        source = ROOT / name
        if source.is_file():  # a tracked file deleted in the working tree is left out
            target = clone / name
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, target)
    return clone


def test_the_first_steps_are_simulated_commands_the_cli_has() -> None:
    commands = first_steps(README.read_text(encoding="utf-8"))
    assert [c.split()[:2] for c in commands] == [
        ["mkdir", "-p"],
        ["skyquill", "plan"],
        ["skyquill", "fly"],
        ["skyquill", "plan"],
        ["skyquill", "demo"],
    ]


def test_every_command_of_the_readme_table_exists() -> None:
    named = table_commands(README.read_text(encoding="utf-8"))
    assert {"plan", "fly", "demo", "up", "down", "submit", "status", "tui", "kiosk"} <= named
    assert named <= set(_discover()), named - set(_discover())


@pytest.mark.multiprocess
@pytest.mark.slow
@pytest.mark.timeout(240)
def test_the_first_steps_run_clean_on_a_fresh_clone(tmp_path: Path) -> None:
    clone = fresh_clone(tmp_path)
    assert not (clone / "out").exists() and (clone / "shows" / "airshow-2014.yaml").is_file()
    env = {**os.environ, "PYTHONPATH": str(clone)}
    env.pop("PYTHONWARNINGS", None)  # what a newcomer's shell has
    where = subprocess.run(
        [str(VENV_BIN / "python"), "-c", "import cli; print(cli.__file__)"],
        cwd=clone,
        env=env,
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    assert Path(where).is_relative_to(clone), where  # the copy's code, not this checkout's

    for command in first_steps((clone / "README.md").read_text(encoding="utf-8")):
        argv = shlex.split(command)
        if argv[0] == "skyquill":
            argv[0] = str(VENV_BIN / "skyquill")
        done = subprocess.run(argv, cwd=clone, env=env, capture_output=True, text=True, timeout=180)
        printed = done.stdout + done.stderr
        assert done.returncode == 0, f"{command}\n{printed}"  # the demo: 0 only if all written
        assert not NOISE.search(printed), f"{command}\n{printed}"

    out = clone / "out"
    for written in ("TRAJ.json", "plan.png", "fly/metrics.json", "fly/report.png", "PLAN.json"):
        assert (out / written).stat().st_size > 0, written
    (demo,) = (out / "demo").iterdir()
    assert len(list((demo / "jobs").glob("*/report.png"))) == 2
    for log in (demo / "logs").iterdir():  # the show's own processes: no traceback either
        text = log.read_text(encoding="utf-8", errors="replace")
        found = NOISE.search(text)
        assert found is None, f"{log}:\n{text[max(0, found.start() - 1500) : found.end() + 1500]}"

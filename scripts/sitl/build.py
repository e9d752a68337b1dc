"""Build ArduCopter or PX4 SIH SITL from a checkout you point it at, listening on loopback only.

    .venv/bin/python scripts/sitl/build.py px4 ~/src/PX4-Autopilot      # v1.16: ~3-6 min on 2 cores
    .venv/bin/python scripts/sitl/build.py ardupilot ~/src/ardupilot    # 4.7: ~21-27 min on 2 cores

The checkout must hold the submodules its SITL build needs (``git submodule update --init
--recursive``, or the command this prints when one is missing or holds only its ``.git`` link);
nothing is fetched. The script applies scripts/sitl/source_edits.py to the checkout (loopback
binds; PX4: two board options off and SIH's airframe vibration as the parameter SIH_IMU_VIB; an
edit already there is left as it is), creates a Python environment for the build tools beside the
checkout (``<checkout>/.skyquill-build-venv``, from PyPI), builds under ``nice`` and prints the
``export SKYQUILL_..._SITL=...`` line for the tests and scripts/sitl/start.py. Nothing of the
checkout or the binary goes into this repository. ``--edits-only`` stops after the edits. The
build stops at the first step that fails, also one that says so only in its output and exits 0
(``Recipe.quiet_failures``): the next step would fail later, with a less telling message.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from source_edits import ARDUPILOT_EDITS, PX4_EDITS, Edit, EditError, apply_edits

BUILD_VENV = ".skyquill-build-venv"
BUILD_PYTHON_PACKAGES = (
    "empy==3.3.4",  # both projects' generators use the 3.x API
    "future",
    "pexpect",
    "kconfiglib",
    "jinja2",
    "pyyaml",
    "jsonschema",
    "pyros-genmsg",
    "packaging",
    "lxml",
)
"""What the two builds' code generators import (ArduPilot's waf and mavgen; PX4's Kconfig, uORB,
parameters and ROMFS generators)."""


@dataclass(frozen=True)
class Recipe:
    """How one autopilot's SITL is built."""

    marker: str
    """A file only this project's checkout has, relative to its root."""
    submodules: tuple[str, ...]
    """Submodule directories the SITL build needs (each must hold more than its ``.git``)."""
    edits: tuple[Edit, ...]
    tools: tuple[str, ...]
    """Programs the build runs, looked up on PATH."""
    steps: tuple[tuple[str, ...], ...]
    """Commands run in the checkout, in order, under ``nice``."""
    quiet_failures: tuple[str, ...]
    """Regular expressions of output lines that mean a step failed although it exited 0."""
    env: tuple[tuple[str, str], ...]
    binary: str
    """The executable built, relative to the root."""
    env_variable: str
    """Where the tests and start.py look for the binary."""


RECIPES = {
    "ardupilot": Recipe(
        marker="ArduCopter/Copter.cpp",
        submodules=(
            "modules/waf",
            "modules/mavlink",
            "modules/mavlink/pymavlink",
            "modules/littlefs",
            "modules/lwip",
            "modules/DroneCAN/DSDL",
            "modules/DroneCAN/dronecan_dsdlc",
            "modules/DroneCAN/libcanard",
            "modules/DroneCAN/pydronecan",
        ),
        edits=ARDUPILOT_EDITS,
        tools=("g++", "gcc", "git"),
        steps=(
            ("./waf", "configure", "--board", "sitl", "--no-submodule-update"),
            ("./waf", "copter", "--no-submodule-update"),
        ),
        # ArduPilot's ./waf wrapper, when modules/waf/waf-light is missing, prints "Missing waf
        # submodule. Trying to get it", runs git submodule update and, if git succeeds, prints
        # "Submodules OK, try running again" and exits 0 having built nothing
        quiet_failures=(r"\bMissing \S+ submodule\b", r"\btry running again\b"),
        # littlefs does not build with -Werror=unused-variable on GCC 12+
        env=(("CFLAGS", "-Wno-unused-variable"), ("CXXFLAGS", "-Wno-unused-variable")),
        binary="build/sitl/bin/arducopter",
        env_variable="SKYQUILL_ARDUCOPTER_SITL",
    ),
    "px4": Recipe(
        marker="src/modules/simulation/simulator_sih/sih.cpp",
        submodules=(
            "src/modules/mavlink/mavlink",
            "src/modules/mavlink/mavlink/pymavlink",  # its mavgen.py makes PX4's MAVLink headers
            "src/lib/events/libevents",
            "src/drivers/gps/devices",
            "src/lib/heatshrink/heatshrink",
        ),
        edits=PX4_EDITS,
        tools=("g++", "gcc", "git", "make", "cmake"),
        steps=(("make", "px4_sitl_default"),),
        quiet_failures=(),  # none known: its failures seen so far exit non-zero
        env=(("GIT_SUBMODULES_ARE_EVIL", "1"),),  # build what is checked out, fetch nothing
        binary="build/px4_sitl_default/bin/px4",
        env_variable="SKYQUILL_PX4_SITL",
    ),
}


class BuildError(Exception):
    """The checkout or the machine cannot build; the message says what is missing."""


def check_checkout(kind: str, root: Path) -> None:
    """BuildError unless ``root`` is a checkout of ``kind`` with the submodules it needs."""
    recipe = RECIPES[kind]
    if not (root / recipe.marker).is_file():
        raise BuildError(f"{root}: not a {kind} checkout (no {recipe.marker})")
    missing = [s for s in recipe.submodules if not submodule_filled(root / s)]
    if missing:
        raise BuildError(
            f"{root}: submodules missing: {', '.join(missing)} "
            f"(git -C {root} submodule update --init --recursive {' '.join(missing)})"
        )


def submodule_filled(path: Path) -> bool:
    """Whether a submodule directory holds its files: a submodule git registered but never
    checked out is an empty directory, or (after an interrupted ``submodule update``) a directory
    with only its ``.git`` link, and either builds nothing."""
    return path.is_dir() and any(entry.name != ".git" for entry in path.iterdir())


def check_tools(kind: str) -> None:
    """BuildError naming the programs the build needs that are not on PATH."""
    missing = [tool for tool in RECIPES[kind].tools if shutil.which(tool) is None]
    if missing:
        raise BuildError(
            f"not on PATH: {', '.join(missing)} (Debian, as root: apt-get install "
            "build-essential cmake git)"
        )


def build_python(root: Path) -> Path:
    """The build tools' Python environment beside the checkout (created once); its bin dir."""
    venv = root / BUILD_VENV
    bin_dir = venv / "bin"
    steps = [[str(bin_dir / "python"), "-m", "pip", "install", "-q", *BUILD_PYTHON_PACKAGES]]
    if not (bin_dir / "python").exists():
        steps.insert(0, [sys.executable, "-m", "venv", str(venv)])
    for step in steps:
        if subprocess.run(step).returncode != 0:
            raise BuildError(f"{' '.join(step[:4])}: failed (see above); PyPI must be reachable")
    return bin_dir


def build(kind: str, root: Path, bin_dir: Path) -> Path:
    """Run the recipe's steps under ``nice`` in ``root``, stopping at the first that fails; the
    built binary."""
    recipe = RECIPES[kind]
    env = dict(os.environ)
    env.update(recipe.env)
    env["PATH"] = f"{bin_dir}{os.pathsep}{env.get('PATH', '')}"
    env["PYTHONUNBUFFERED"] = "1"  # the tools' Python output reaches the user as it comes
    for step in recipe.steps:
        print(f"$ nice -n 10 {' '.join(step)}", flush=True)
        t0 = time.monotonic()
        returncode, quiet_failure = run_step(step, root, env, recipe.quiet_failures)
        if returncode != 0:
            raise BuildError(f"{' '.join(step)} failed (exit {returncode}): see above")
        if quiet_failure is not None:
            raise BuildError(f"{' '.join(step)} failed (exit 0, but it said: {quiet_failure})")
        print(f"  {time.monotonic() - t0:.0f} s", flush=True)
    binary = root / recipe.binary
    if not binary.is_file():
        raise BuildError(f"the build ended but {binary} is missing")
    return binary


def run_step(
    step: tuple[str, ...], root: Path, env: dict[str, str], quiet_failures: tuple[str, ...]
) -> tuple[int, str | None]:
    """Run one step under ``nice``, its output (stderr merged) shown as it comes and read for a
    failure its exit code does not tell; (exit code, the first such output line or None)."""
    command = ["nice", "-n", "10", *step]
    first_failure: str | None = None
    with subprocess.Popen(
        command, cwd=root, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT
    ) as process:
        assert process.stdout is not None
        for raw in process.stdout:
            line = raw.decode(errors="replace")
            print(line, end="", flush=True)
            if first_failure is None and says_failed(line, quiet_failures):
                first_failure = line.strip()
    return process.returncode, first_failure


def says_failed(line: str, quiet_failures: tuple[str, ...]) -> bool:
    """Whether an output line matches one of a recipe's ``quiet_failures``."""
    return any(re.search(pattern, line) for pattern in quiet_failures)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("autopilot", choices=sorted(RECIPES))
    parser.add_argument("checkout", type=Path, help="root of the ArduPilot or PX4 source tree")
    parser.add_argument(
        "--edits-only", action="store_true", help="apply the source edits, build nothing"
    )
    args = parser.parse_args(argv)
    root = args.checkout.expanduser().resolve()
    try:
        check_checkout(args.autopilot, root)
        for edit, outcome in apply_edits(root, RECIPES[args.autopilot].edits):
            print(f"{outcome:>8}: {edit.path}: {edit.why}")
        if args.edits_only:
            return 0
        check_tools(args.autopilot)
        binary = build(args.autopilot, root, build_python(root))
    except (BuildError, EditError) as err:
        print(f"build.py: {err}", file=sys.stderr)
        return 2
    print(f"export {RECIPES[args.autopilot].env_variable}={binary}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

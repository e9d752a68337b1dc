"""What one-off commands import (a fresh interpreter each): only what the command at hand needs,
so that ``skyquill plan --text 永`` does not pay for Latin fonts, plotting or show-file models."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from cli.main import main

ROOT = Path(__file__).resolve().parents[1]


def _probe(code: str, env: dict[str, str] | None = None) -> Any:
    """Run ``code`` in a fresh interpreter from the repository root; its last stdout line, as
    JSON."""
    full_env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    full_env.update(PYTHONPATH=str(ROOT), **(env or {}))
    out = subprocess.run(
        [sys.executable, "-c", code],
        cwd=ROOT,
        env=full_env,
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def _loaded(prefixes: tuple[str, ...]) -> str:
    """Code printing the loaded modules that start with one of ``prefixes``."""
    return f"print(json.dumps(sorted(m for m in sys.modules if m.startswith({prefixes!r}))))"


def test_plan_of_chinese_text_imports_no_font_plot_or_show_models() -> None:
    unwanted = ("HersheyFonts", "matplotlib", "pydantic", "yaml", "showfile")
    unwanted += ("planner.retime", "planner.lbfgs")  # the paper's re-segmentation: not the default
    unwanted += ("numpy.ma.",)  # np.unique loads numpy.ma (10 ms): a plan needs no masked arrays
    unwanted += ("shutil", "glob")  # 2-3 ms: argparse's help width, the OpenBLAS file's name
    flight = ("loop", "world", "dynamics", "autopilot_pen")  # the closed loop: flights, not plans
    flight += ("control.controller", "control.tip")  # the control law: the settings hold its config
    unwanted += tuple(f"vehicles.quadrotor_brush.{name}" for name in flight)
    code = (
        "import contextlib, io, json, os, sys\n"
        "from cli.main import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    assert main(['plan', '--text', '永']) == 0\n" + _loaded(unwanted)
    )
    assert _probe(code) == []


@pytest.mark.parametrize("text", ["永", "A", "国"])
def test_plan_of_one_character_imports_no_scipy(text: str) -> None:
    """The command solves its QPs on PIQP's dense interface and its band systems in numpy:
    importing scipy (0.2-0.3 s) would cost it more than the plan itself. The longest characters
    turn sparse, as the dense budget's rule has them (planner.fit_qp): 鬱 (342 control points
    per axis) is predicted 147 ms dense for its fit's four axis QPs and 236 ms for its time
    law's (109 ms measured) against the command's 0.2 s."""
    code = (
        "import contextlib, io, json, sys\n"
        "from cli.main import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        f"    assert main(['plan', '--text', {text!r}]) == 0\n" + _loaded(("scipy",))
    )
    assert _probe(code) == []


@pytest.mark.parametrize("columns", [None, "50", "120"])
def test_help_is_laid_out_as_argparse_does_without_importing_shutil(columns: str | None) -> None:
    code = (
        "import argparse, contextlib, io, json, sys\n"
        "from cli.main import main\n"
        "out = io.StringIO()\n"
        "with contextlib.redirect_stdout(out), contextlib.suppress(SystemExit):\n"
        "    main(['plan', '--help'])\n"
        "ours = 'shutil' in sys.modules\n"
        "import cli.cmd_plan as command\n"
        "parser = argparse.ArgumentParser(prog='skyquill plan', description=command.HELP)\n"
        "command.add_arguments(parser)\n"
        "print(json.dumps([ours, out.getvalue() == parser.format_help()]))"
    )
    env = {"COLUMNS": columns} if columns else {}
    assert _probe(code, env) == [False, True]


def test_plan_asks_for_one_blas_thread_before_numpy_loads() -> None:
    code = (
        "import json, os, sys\n"
        "import cli.cmd_plan\n"
        "loaded_early = 'numpy' in sys.modules\n"
        "cli.cmd_plan._one_blas_thread()\n"
        "print(json.dumps([loaded_early, os.environ.get('OPENBLAS_NUM_THREADS')]))"
    )
    assert _probe(code) == [False, "1"]
    assert _probe(code, {"OPENBLAS_NUM_THREADS": "2"}) == [False, "2"]  # the user's wins


def test_plan_with_one_blas_thread_is_the_plan_of_the_default_threads(tmp_path: Path) -> None:
    """The command (one BLAS thread) writes the plan this process (numpy already loaded with
    its default threads) writes, all but the timings."""
    one, default = tmp_path / "one.json", tmp_path / "default.json"
    code = (
        "import contextlib, io, json, os\n"
        "from cli.main import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        f"    main(['plan', '--text', '永', '--out', {str(one)!r}])\n"
        "print(json.dumps(os.environ.get('OPENBLAS_NUM_THREADS')))"
    )
    assert _probe(code) == "1"
    assert main(["plan", "--text", "永", "--out", str(default)]) == 0
    docs = [json.loads(path.read_text()) for path in (one, default)]
    for doc in docs:
        doc.pop("timing_ms")
    assert docs[0] == docs[1]


def test_status_imports_neither_numpy_nor_pydantic(tmp_path: Path) -> None:
    """Up to asking the orchestrator (here nobody answers: no router, no retry), then decoding
    a snapshot as large as a busy show's (500 jobs with errors, 250 vehicles)."""
    show = tmp_path / "show.yaml"
    text = (ROOT / "shows" / "solo.yaml").read_text(encoding="utf-8")
    text = text.replace("tcp/127.0.0.1:7448", "tcp/127.0.0.1:9")  # the discard port: no router
    text = text.replace("mode: mtls", "mode: none")
    text = text.replace(
        "multicast_scouting: false", "multicast_scouting: false\n  open_timeout_s: 0"
    )
    show.write_text(text, encoding="utf-8")
    unwanted = ("numpy", "pydantic", "showfile.models", "orchestrator.core", "asyncio")
    code = (
        "import contextlib, io, json, sys\n"
        "from cli.main import main\n"
        "with contextlib.redirect_stderr(io.StringIO()) as err:\n"
        f"    assert main(['status', {str(show)!r}, '--timeout', '0.1']) == 2\n"
        "assert 'skyquill status' in err.getvalue(), err.getvalue()\n"
        "from bus.codec import decode\n"
        "from bus.messages import ShowSnapshot\n"
        "error = dict(code='plan_failed', message='too wide', field='text')\n"
        "jobs = [dict(job_id=f'j{k}', state='done', label='永', kind='text', client_id='c',\n"
        "             created_at_s=1.0, updated_at_s=2.0, error=error) for k in range(500)]\n"
        "vehicles = [dict(vehicle_id=f'u{k}', kind='quadrotor-brush', state='idle', alive=True)\n"
        "            for k in range(250)]\n"
        "raw = json.dumps(dict(show_id='s', time_s=0.0, queue_paused=False, jobs=jobs,\n"
        "                      vehicles=vehicles, job_counts={'done': 500}))\n"
        "assert len(decode(raw, ShowSnapshot).jobs) == 500\n" + _loaded(unwanted)
    )
    assert _probe(code) == []

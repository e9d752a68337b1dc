"""What reaching a kind imports (a fresh interpreter each): the registry and the interface load no
numerics, and planning a job loads no simulator (a kiosk preview or an orchestrator's estimate
must not pay for MuJoCo)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _loaded_after(code: str, heavy: tuple[str, ...]) -> list[str]:
    """The modules of the packages ``heavy`` loaded once ``code`` has run in a fresh interpreter
    from the repository root."""
    probe = (
        f"import json, sys\n{code}\n"
        f"print(json.dumps(sorted(m for m in sys.modules if m.split('.')[0] in {heavy!r})))"
    )
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    out = subprocess.run(
        [sys.executable, "-c", probe], cwd=ROOT, env=env, capture_output=True, text=True, check=True
    )
    loaded: list[str] = json.loads(out.stdout.strip().splitlines()[-1])
    return loaded


def test_the_registry_and_the_interface_load_no_numerics() -> None:
    code = "import vehicles.registry, vehicles.kind"
    assert _loaded_after(code, ("numpy", "planner", "mujoco", "casadi")) == []


@pytest.mark.parametrize(
    ("show", "unwanted"),
    [("ground-writers.yaml", ("mujoco", "casadi")), ("flying-calligrapher.yaml", ("mujoco",))],
)
def test_planning_a_job_loads_no_simulator(show: str, unwanted: tuple[str, ...]) -> None:
    """Planning on the floor needs the planner alone; on a wall, CasADi, but no MuJoCo."""
    code = (
        "from planner.glyphs import text_glyph\n"
        "from showfile import load_show\n"
        "from vehicles.jobs import plan_job\n"
        f"show = load_show('shows/{show}')\n"
        "job = plan_job(show, show.vehicles[0].id, text_glyph('L'))\n"
        "assert job.plan.duration_s > 0.0"
    )
    assert _loaded_after(code, (*unwanted, "matplotlib")) == []

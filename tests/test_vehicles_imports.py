"""What reaching a kind imports (a fresh interpreter each): the registry and the interface load no
numerics."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

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

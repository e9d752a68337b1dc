"""Scripts and benchmarks are not packages: the tests load them from their files, once each."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType


def load_module(name: str, path: Path) -> ModuleType:
    """The module ``name`` from ``path``, loaded on first use and kept in ``sys.modules`` (its
    dataclasses look their module up there while being built; a later call reuses it)."""
    module = sys.modules.get(name)
    if module is None:
        spec = importlib.util.spec_from_file_location(name, path)
        assert spec is not None and spec.loader is not None, path
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return module

"""Entry point of the ``skyquill`` command.

Every module ``cli/cmd_*.py`` is a subcommand. It defines ``NAME`` (the subcommand), optionally
``ALIASES`` (other names, space-separated), ``HELP`` (one line), ``add_arguments(parser)`` and
``run(args) -> int`` (the exit status). Modules are imported only when their subcommand runs, so
a heavy dependency of one command never slows another; a subcommand named after its file
(``sim-mavlink`` -> ``cmd_sim_mavlink.py``) is found without reading the other files.
"""

from __future__ import annotations

import argparse
import ast
import importlib
import os
import sys
from pathlib import Path
from types import ModuleType
from typing import Any, NoReturn

_PACKAGE_DIR = Path(__file__).parent


def _discover() -> dict[str, tuple[str, str]]:
    """Map subcommand name -> (module name, help line), read without importing the modules."""
    commands: dict[str, tuple[str, str]] = {}
    for path in sorted(_PACKAGE_DIR.glob("cmd_*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        constants: dict[str, str] = {}
        for node in tree.body:
            if (
                isinstance(node, ast.Assign)
                and len(node.targets) == 1
                and isinstance(node.targets[0], ast.Name)
                and isinstance(node.value, ast.Constant)
                and isinstance(node.value.value, str)
            ):
                constants[node.targets[0].id] = node.value.value
        name = constants.get("NAME", path.stem.removeprefix("cmd_").replace("_", "-"))
        commands[name] = (f"cli.{path.stem}", constants.get("HELP", ""))
        for alias in constants.get("ALIASES", "").split():  # e.g. ``stop`` for ``down``
            commands[alias] = (f"cli.{path.stem}", f"same as {name}")
    return dict(sorted(commands.items()))


def _terminal_columns() -> int:
    """The terminal's width as ``shutil.get_terminal_size`` reads it (``COLUMNS``, then the
    terminal of stdout, else 80), without importing ``shutil``."""
    try:
        columns = int(os.environ.get("COLUMNS", "0"))
    except ValueError:
        columns = 0
    if columns <= 0 and sys.__stdout__ is not None:
        try:
            columns = os.get_terminal_size(sys.__stdout__.fileno()).columns
        except (AttributeError, ValueError, OSError):
            columns = 0
    return columns if columns > 0 else 80


class HelpLayout(argparse.HelpFormatter):
    """argparse's help layout at the terminal's width, read without ``shutil``: argparse
    imports it (with ``bz2``, ``lzma`` and ``fnmatch``) for every parser it checks, 2-3 ms of
    every command (2026-12-02)."""

    def __init__(self, prog: str) -> None:
        super().__init__(prog, width=_terminal_columns() - 2)


class OneLineParser(argparse.ArgumentParser):
    """An argument parser whose error is one line naming what was wrong and the way out
    (``skyquill fly: argument --wind: not a number: 'abc' (see skyquill fly --help)``), not
    the usage block above it; ``--help`` is argparse's own, laid out by :class:`HelpLayout`."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", HelpLayout)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: {message} (see {self.prog} --help)\n")


def build_parser() -> tuple[argparse.ArgumentParser, dict[str, str]]:
    parser = OneLineParser(
        prog="skyquill",
        description="Show orchestration for fleets of vehicles that write.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    modules: dict[str, str] = {}
    for name, (module_name, help_line) in _discover().items():
        modules[name] = module_name
        sub.add_parser(name, help=help_line, add_help=False)
    return parser, modules


def _named_module(name: str) -> ModuleType | None:
    """The module of subcommand ``name`` when its file is named after it, else None."""
    stem = "cmd_" + name.replace("-", "_")
    if not stem.isidentifier() or not (_PACKAGE_DIR / f"{stem}.py").is_file():
        return None
    module = importlib.import_module(f"cli.{stem}")
    names = [getattr(module, "NAME", name), *getattr(module, "ALIASES", "").split()]
    return module if name in names else None


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        return _run(argv)
    except KeyboardInterrupt:  # Ctrl-C: one line, no traceback (cli/interrupt.py)
        print(f"{' '.join(['skyquill', *argv[:1]])}: interrupted", file=sys.stderr)
        _exit_now(130)
        raise  # not reached


def _run(argv: list[str]) -> int:
    module = _named_module(argv[0]) if argv else None
    if module is None:
        parser, modules = build_parser()
        if not argv or argv[0] not in modules:
            parser.parse_args(argv or ["--help"])
            return 2
        module = importlib.import_module(modules[argv[0]])
    name = argv[0]
    command_parser = OneLineParser(prog=f"skyquill {name}", description=module.HELP)
    module.add_arguments(command_parser)
    args = command_parser.parse_args(argv[1:])
    return int(module.run(args))


def _exit_now(status: int) -> None:
    """Leave at once, skipping the interpreter's teardown: everything the command opened is
    closed by now, and after a show (Zenoh's runtime, a few hundred modules) the teardown took
    2.6 s of a Ctrl-C's 3.3 s (``skyquill demo``, load 5.7)."""
    logging = sys.modules.get("logging")  # not imported here: it cost every command 6 ms
    if logging is not None:
        logging.shutdown()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)


if __name__ == "__main__":
    raise SystemExit(main())

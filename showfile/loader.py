"""Read a show file: YAML -> :class:`Show`, with errors naming file, line and field.

The YAML is composed into nodes first (they keep line numbers), then constructed into plain data
and validated by pydantic; every validation error's location (``("vehicles", 2, "board")``) is
mapped back to its YAML node. Cross-checks (showfile/checks.py) report the same way.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pydantic
import yaml

from showfile.checks import Loc, cross_check
from showfile.errors import ShowError
from showfile.models import Show


@dataclass(frozen=True)
class ShowProblem:
    """One thing wrong in a show file."""

    file: str
    """The show file (as given to the loader)."""
    line: int | None
    """1-based line of the offending field, or of its enclosing block when the field is missing."""
    field: str
    """Dotted path of the field, e.g. ``vehicles[2].board``; empty for the whole document."""
    message: str
    """What is wrong."""

    def __str__(self) -> str:
        where = f"{self.file}:{self.line}" if self.line is not None else self.file
        return f"{where}: {self.field or '(document)'}: {self.message}"


class ShowFileError(ShowError):
    """The show file is unreadable or invalid; ``problems`` lists every problem found."""

    def __init__(self, problems: Sequence[ShowProblem]) -> None:
        self.problems = tuple(problems)
        first = self.problems[0] if self.problems else None
        self.file = first.file if first else ""
        self.line = first.line if first else None
        self.field = first.field if first else ""
        lines = "\n".join(f"  {p}" for p in self.problems)
        super().__init__(f"invalid show file ({len(self.problems)} problem(s)):\n{lines}")


def format_loc(loc: Iterable[str | int]) -> str:
    """``("vehicles", 2, "board")`` -> ``vehicles[2].board``."""
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += f".{part}" if out else str(part)
    return out


def _line_of(root: yaml.Node | None, loc: Loc) -> int | None:
    """Line of the node at ``loc`` (or of the deepest enclosing node that exists)."""
    if root is None:
        return None
    node: yaml.Node = root
    line: int = int(node.start_mark.line) + 1
    for part in loc:
        child: yaml.Node | None = None
        if isinstance(node, yaml.MappingNode):
            for key_node, value_node in node.value:
                if key_node.value == str(part):
                    child = value_node
                    line = int(key_node.start_mark.line) + 1
                    break
        elif (
            isinstance(node, yaml.SequenceNode)
            and isinstance(part, int)
            and 0 <= part < len(node.value)
        ):
            child = node.value[part]
            line = int(child.start_mark.line) + 1
        if child is None:
            break
        node = child
    return line


def _duplicate_keys(node: yaml.Node | None, file: str, loc: Loc = ()) -> list[ShowProblem]:
    problems: list[ShowProblem] = []
    if isinstance(node, yaml.MappingNode):
        seen: set[str] = set()
        for key_node, value_node in node.value:
            key = str(key_node.value)
            if key in seen:
                problems.append(
                    ShowProblem(
                        file,
                        key_node.start_mark.line + 1,
                        format_loc((*loc, key)),
                        "duplicate key",
                    )
                )
            seen.add(key)
            problems += _duplicate_keys(value_node, file, (*loc, key))
    elif isinstance(node, yaml.SequenceNode):
        for index, item in enumerate(node.value):
            problems += _duplicate_keys(item, file, (*loc, index))
    return problems


def _compose(text: str, file: str) -> tuple[yaml.Node | None, Any]:
    loader = yaml.SafeLoader(text)
    try:
        node = loader.get_single_node()
        data = loader.construct_document(node) if node is not None else None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line = mark.line + 1 if mark is not None else None
        raise ShowFileError(
            [ShowProblem(file, line, "", f"YAML syntax: {exc.problem or exc}")]
        ) from None
    except yaml.YAMLError as exc:
        raise ShowFileError([ShowProblem(file, None, "", f"YAML: {exc}")]) from None
    finally:
        loader.dispose()
    return node, data


def _pydantic_problems(
    exc: pydantic.ValidationError, root: yaml.Node | None, file: str
) -> list[ShowProblem]:
    problems = []
    for error in exc.errors(include_url=False):
        loc: Loc = tuple(error["loc"])
        message = str(error["msg"])
        if error["type"] == "missing":
            message = f"required field {loc[-1]!r} is missing" if loc else message
        elif error["type"] == "extra_forbidden":
            message = "unknown field"
        elif (
            "input" in error
            and not isinstance(error["input"], dict | list)
            and repr(error["input"]) not in message  # an unknown kind's message names it
        ):
            message = f"{message} (got {error['input']!r})"
        line = _line_of(root, loc[:-1] if error["type"] == "missing" else loc)
        problems.append(ShowProblem(file, line, format_loc(loc), message))
    return problems


def parse_show(text: str, *, file: str = "<show>") -> Show:
    """Validate show-file text; raises :class:`ShowFileError` listing every problem."""
    root, data = _compose(text, file)
    problems = _duplicate_keys(root, file)
    if problems:
        raise ShowFileError(problems)
    if not isinstance(data, dict):
        raise ShowFileError([ShowProblem(file, 1, "", "a show file is a YAML mapping")])
    if "source_path" in data:
        line = _line_of(root, ("source_path",))
        raise ShowFileError([ShowProblem(file, line, "source_path", "unknown field")])
    try:
        show = Show.model_validate(data)
    except pydantic.ValidationError as exc:
        raise ShowFileError(_pydantic_problems(exc, root, file)) from None
    cross = [
        ShowProblem(file, _line_of(root, loc), format_loc(loc), message)
        for loc, message in cross_check(show)
    ]
    if cross:
        raise ShowFileError(cross)
    return show


def load_show(path: str | Path) -> Show:
    """Read and validate a show file; raises :class:`ShowFileError` naming file, line and field.

    The show keeps ``path`` as ``source_path``: its relative paths start from that file's folder."""
    file = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise ShowFileError([ShowProblem(file, None, "", f"cannot read: {exc}")]) from None
    show = parse_show(text, file=file)
    return show.model_copy(update={"source_path": Path(path)})


def dump_show(show: Show, path: str | Path | None = None) -> str:
    """The show as YAML text (written to ``path`` when given): temporary shows in tests.

    ``load_show(path)`` of the result gives back an equal show (apart from ``source_path``), whose
    relative paths start from ``path``'s folder (``showfile/paths.py``), not the original's.
    """
    data = show.model_dump(mode="json", exclude_none=True, exclude={"source_path"})
    text: str = yaml.safe_dump(data, sort_keys=False, allow_unicode=True)
    if path is not None:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        Path(path).write_text(text, encoding="utf-8")
    return text

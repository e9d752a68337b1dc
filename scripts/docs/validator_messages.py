"""The error messages of the show file's checks, read from their source (``ast``): so that the
reference lists every check without a second copy of its words."""

from __future__ import annotations

import ast
import inspect
import sys
import textwrap
from collections.abc import Callable
from typing import Any


def messages_of(func: Callable[..., Any]) -> list[str]:
    """The error messages a validator or check can give, read from its source: what it raises,
    what it assigns as the reason, and the message of each ``(field, message)`` problem."""
    function = getattr(func, "__func__", func)
    tree = ast.parse(textwrap.dedent(inspect.getsource(function)))
    found: list[tuple[int, str]] = []
    for node in ast.walk(tree):
        text: ast.expr | None = None
        if isinstance(node, ast.Raise) and isinstance(node.exc, ast.Call) and node.exc.args:
            text = node.exc.args[0]
        elif isinstance(node, ast.Assign) and isinstance(node.value, ast.JoinedStr):
            text = node.value
        elif (
            isinstance(node, ast.Tuple)
            and len(node.elts) == 2
            and isinstance(node.elts[0], ast.Tuple)
        ):
            text = node.elts[1]
        if text is None:
            continue
        message = _string_of(text)
        if message and " " in message and message not in [m for _, m in found]:
            found.append((text.lineno, message))
    return [message for _, message in sorted(found)]


def _string_of(node: ast.expr) -> str | None:
    """A literal or f-string message, its interpolations as ``{name}`` or ``…`` (not ``<name>``,
    which Markdown takes for an HTML tag)."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return node.value
    if not isinstance(node, ast.JoinedStr):
        return None
    parts = []
    for value in node.values:
        if isinstance(value, ast.Constant):
            parts.append(str(value.value))
        elif isinstance(value, ast.FormattedValue):
            inner = value.value
            simple = isinstance(inner, (ast.Name, ast.Attribute))
            parts.append(f"{{{ast.unparse(inner)}}}" if simple else "…")
    return "".join(parts)


def cross_checks(entry: Callable[..., Any]) -> list[Callable[..., Any]]:
    """``entry`` and the functions of its own module it calls, in the order it calls them."""
    module = sys.modules[entry.__module__]
    called = [entry]
    for node in ast.walk(ast.parse(textwrap.dedent(inspect.getsource(entry)))):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
            function = getattr(module, node.func.id, None)
            if not inspect.isfunction(function) or function in called:
                continue
            if function.__module__ == module.__name__:
                called.append(function)
    return called

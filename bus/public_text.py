"""Text from the public is plain text: checked when a submission is decoded (pure).

What a submitter names, the ``client_id`` and a strokes document's ``label`` and ``device``, and
the typed ``text`` reach the operator's terminal, the console, logs and the event history. At
decode (:class:`bus.messages.SubmitRequest`) a submission is refused when any of them holds:

- a control character (C0, DEL, C1: ``ESC`` starts every terminal escape sequence), a line or
  paragraph separator, a lone surrogate;
- a format character that reorders or hides text (bidirectional embeddings, overrides, isolates
  and marks, U+202A-202E, U+2066-2069, tag characters, BOM); zero-width (non-)joiners stay, as
  emoji and several scripts need them;
- in a name (not in typed text), Rich or Textual markup: a ``[...]`` span. Typed text keeps its
  brackets: they are written on the board (the Hershey font has them), and every view shows a
  label as plain text.

Lengths are capped by the message's field types (``MAX_CLIENT_ID_CHARS``, ``MAX_LABEL_CHARS``).
"""

from __future__ import annotations

import re
import unicodedata

__all__ = ["MAX_CLIENT_ID_CHARS", "MAX_LABEL_CHARS", "text_problem"]

MAX_CLIENT_ID_CHARS = 100
"""Longest ``client_id`` of a submission."""
MAX_LABEL_CHARS = 200
"""Longest ``label`` or ``device`` of a strokes document."""
_JOINERS = frozenset("\u200c\u200d")
_REFUSED_CATEGORIES = frozenset(("Cc", "Cf", "Cs", "Zl", "Zp"))
_MARKUP = re.compile(r"\[[^\[\]]*\]")


def drawing_label(strokes: int) -> str:
    """The label of a drawing (``docs/protocol.md``): its stroke count, never its own words."""
    return f"drawing ({strokes} stroke{'' if strokes == 1 else 's'})"


def _refused(ch: str) -> bool:
    return unicodedata.category(ch) in _REFUSED_CATEGORIES and ch not in _JOINERS


def text_problem(value: str, *, name: bool) -> str | None:
    """Why ``value`` is not plain text, in a few words, or None; ``name``: a client id or a
    label (markup refused), else typed text (brackets allowed)."""
    if not value.isprintable():  # fast path: every refused character is unprintable
        bad = next((ch for ch in value if _refused(ch)), None)
        if bad is not None:
            return f"holds U+{ord(bad):04X} ({unicodedata.name(bad, 'a control character')})"
    if name and _MARKUP.search(value):
        return "holds markup (a [...] span)"
    return None

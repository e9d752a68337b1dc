"""Strings from the bus shown as plain data: never markup, never terminal codes, never unbounded.

Everything a widget shows that the console did not write itself (job labels, client ids, vehicle
ids and messages, event texts, error messages, the orchestrator's answers) came over the bus, and
much of it from the public. :func:`clean` makes such a string safe to put on screen, and
:func:`plain` wraps it in a :class:`rich.text.Text`, which Rich and Textual never parse as markup.
Widgets use these two and never hand a bus string to anything that parses markup (``Static``,
``DataTable`` string cells, ``border_title``, ``notify`` and Rich tables all do by default).

- control characters (C0, DEL, C1) become visible: ``\\x1b`` reads ``␛``, ``\\n`` reads ``␊``, so an
  escape sequence or a carriage return cannot move the cursor, recolour or overwrite the screen;
- invisible format characters (bidirectional overrides, embeddings, isolates and marks, tag
  characters, byte order marks), line and paragraph separators and lone surrogates become
  ``\\ufffd``, so no text can reorder or hide what is drawn after it; zero-width (non-)joiners stay,
  as emoji and several scripts need them;
- anything longer than ``max_chars`` characters is cut with an ellipsis before any other work, so
  a 10 kB label costs no more than a short one.
"""

from __future__ import annotations

import unicodedata

from rich.text import Text

MAX_CHARS = 200
"""Longest bus string shown anywhere, in characters (views cut further to their own widths)."""
ELLIPSIS = "…"
REPLACEMENT = "\ufffd"
_JOINERS = frozenset("\u200c\u200d")
"""Zero-width non-joiner and joiner: format characters that real text needs."""


def _visible(ch: str) -> str:
    """A safe stand-in for one character that :meth:`str.isprintable` refused."""
    code = ord(ch)
    if code < 0x20:
        return chr(0x2400 + code)  # the Control Pictures block: ␀ ... ␟
    if code == 0x7F:
        return "\u2421"  # ␡
    category = unicodedata.category(ch)
    if category == "Zs" or category in ("Co", "Cn") or ch in _JOINERS:
        return ch  # spaces (U+3000 ...), private use and unassigned code points draw as glyphs
    return REPLACEMENT  # C1 controls, format characters (bidi, tags, BOM), Zl/Zp, surrogates


def clean(value: object, max_chars: int = MAX_CHARS) -> str:
    """``value`` as one line of plain text at most ``max_chars`` characters long (see module)."""
    text = value if isinstance(value, str) else str(value)
    if len(text) > max_chars:
        text = text[: max(0, max_chars - 1)] + ELLIPSIS
    if text.isprintable():
        return text
    return "".join(ch if ch.isprintable() else _visible(ch) for ch in text)


def plain(value: object, style: str = "", max_chars: int = MAX_CHARS) -> Text:
    """:func:`clean` ``value`` as a Rich ``Text`` (shown literally, whatever brackets it holds)."""
    return Text(clean(value, max_chars), style=style)

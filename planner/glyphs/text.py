"""Typed text in: one line of Latin (Hershey) and Chinese (Make Me a Hanzi) characters.

A character is looked up in the Chinese store before the Hershey font: no built-in Hershey font
shares a character with the store or has U+3000 (tests/test_glyphs_text.py), so the order does
not change the result, and a Chinese text never loads a Hershey font (about 40 ms).
"""

from __future__ import annotations

import numpy as np

from planner.errors import PlannerError
from planner.glyphs.glyph import FloatArray, Glyph
from planner.glyphs.hanzi import HANZI_SOURCE, hanzi_strokes_em, has_hanzi
from planner.glyphs.hershey import DEFAULT_LATIN_FONT, has_latin, latin_char

MAX_TEXT_CHARS = 64
"""Longest text accepted: a short word or name, written on one line."""
IDEOGRAPHIC_SPACE = "\u3000"
"""A blank as wide as one CJK cell (1 em)."""


def has_glyph(char: str, *, latin_font: str = DEFAULT_LATIN_FONT) -> bool:
    """True when :func:`text_glyph` accepts ``char`` (a single character; spaces count)."""
    if len(char) != 1:
        return False
    return char == IDEOGRAPHIC_SPACE or has_hanzi(char) or has_latin(char, latin_font)


def text_glyph(text: str, *, latin_font: str = DEFAULT_LATIN_FONT) -> Glyph:
    """Lay ``text`` out left to right on one line, in em, y up, baseline at y = 0.

    A character found in the Hershey font ``latin_font`` is taken from it (ASCII), otherwise
    from the Chinese stroke data (one 1 em cell each). Unknown characters raise PlannerError
    naming the character and its index.
    """
    _check_text(text)
    strokes: list[FloatArray] = []
    pen_x_em = 0.0
    used_latin = used_hanzi = False
    for index, char in enumerate(text):
        char_strokes: tuple[FloatArray, ...]
        if char == IDEOGRAPHIC_SPACE:
            char_strokes, advance_em = (), 1.0
        elif has_hanzi(char):
            char_strokes, advance_em = hanzi_strokes_em(char), 1.0
            used_hanzi = True
        elif has_latin(char, latin_font):
            latin = latin_char(char, latin_font)
            char_strokes, advance_em = latin.strokes, latin.advance_em
            used_latin = used_latin or bool(char_strokes)
        else:
            raise PlannerError(
                f"no glyph for character {char!r} (U+{ord(char):04X}) at index {index} of {text!r}",
                field="text",
            )
        strokes.extend(s + np.array([pen_x_em, 0.0]) for s in char_strokes)
        pen_x_em += advance_em
    if not strokes:
        raise PlannerError(f"{text!r} has nothing to write (only spaces)", field="text")
    return Glyph(
        strokes=tuple(strokes),
        times_s=(None,) * len(strokes),
        units="em",
        label=text,
        source=_source_name(latin_font, used_latin, used_hanzi),
    )


def _check_text(text: str) -> None:
    if not isinstance(text, str):
        raise PlannerError(f"text must be a string, got {type(text).__name__}", field="text")
    if not text:
        raise PlannerError("text is empty", field="text")
    if len(text) > MAX_TEXT_CHARS:
        raise PlannerError(
            f"text too long ({len(text)} characters, limit {MAX_TEXT_CHARS})", field="text"
        )


def _source_name(latin_font: str, used_latin: bool, used_hanzi: bool) -> str:
    parts = []
    if used_latin:
        parts.append(f"hershey:{latin_font}")
    if used_hanzi:
        parts.append(HANZI_SOURCE)
    return "+".join(parts)

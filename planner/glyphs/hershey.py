"""Latin text in single-line Hershey fonts (PyPI ``Hershey-Fonts``).

Each pen-down polyline of a Hershey glyph becomes one stroke. Coordinates are converted to em
(y up, baseline at y = 0) so that Latin and Chinese characters can share one line: one Hershey
unit is 1/30 em, which puts the cap height (21 units) at 0.7 em of a 1 em CJK cell.

``HersheyFonts`` is imported, and a font decoded, on the first Latin character only: together
about 50 ms that a Chinese text never needs (the archive of the fonts is read twice: for its
names, then for the font).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner.errors import PlannerError
from planner.glyphs.glyph import FloatArray

DEFAULT_LATIN_FONT = "futural"
"""Hershey "Futura light" (roman simplex): one stroke per line, easy to fly."""
EM_PER_HERSHEY_UNIT = 1.0 / 30.0
"""Scale from Hershey font units to em."""


@dataclass(frozen=True, eq=False)
class LatinChar:
    """One Hershey character laid out from x = 0, in em, y up, baseline at y = 0."""

    strokes: tuple[FloatArray, ...]
    """Pen-down polylines, each (n, 2) with n >= 2 distinct consecutive points; may be empty."""
    advance_em: float
    """Horizontal distance to the next character's origin in [em]."""


@functools.cache
def hershey_font_names() -> tuple[str, ...]:
    """Names of the fonts built into Hershey-Fonts."""
    from HersheyFonts import HersheyFonts

    return tuple(str(name) for name in HersheyFonts().default_font_names)


@functools.cache
def _font(name: str) -> tuple[dict[str, Any], float]:
    from HersheyFonts import HersheyFonts

    font = HersheyFonts()
    names = (
        font.default_font_names
    )  # kept by ``font``: loading reads the archive once more, not twice
    if name not in names:
        raise PlannerError(
            f"unknown Hershey font {name!r}; available: {', '.join(names)}", field="latin_font"
        )
    font.load_default_font(name)
    glyphs: dict[str, Any] = font.all_glyphs
    base_line = float(font.render_options["base_line"])
    return glyphs, base_line


def has_latin(char: str, font: str = DEFAULT_LATIN_FONT) -> bool:
    """True when ``font`` has a glyph for the printable character ``char`` (space included)."""
    glyphs, _ = _font(font)
    return char.isprintable() and char in glyphs


@functools.cache
def latin_char(char: str, font: str = DEFAULT_LATIN_FONT) -> LatinChar:
    """The strokes of ``char`` in ``font``; PlannerError if the font has no such glyph."""
    glyphs, base_line = _font(font)
    glyph = glyphs.get(char) if char.isprintable() else None
    if glyph is None:
        raise PlannerError(f"no glyph for {char!r} in Hershey font {font!r}", field="text")
    left = float(glyph.left_offset)
    strokes = []
    for polyline in glyph.strokes:
        pts = np.asarray(polyline, dtype=np.float64).reshape(-1, 2)
        keep = np.r_[True, np.any(np.diff(pts, axis=0) != 0.0, axis=1)]
        pts = pts[keep]
        if pts.shape[0] < 2:
            continue  # a lone point has no ink to fly; no built-in ASCII glyph has one
        em = np.column_stack(
            (
                (pts[:, 0] - left) * EM_PER_HERSHEY_UNIT,
                (base_line - pts[:, 1]) * EM_PER_HERSHEY_UNIT,
            )
        )
        em.flags.writeable = False
        strokes.append(em)
    return LatinChar(
        strokes=tuple(strokes), advance_em=float(glyph.char_width) * EM_PER_HERSHEY_UNIT
    )

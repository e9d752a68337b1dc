"""Glyph sources: handwriting (strokes JSON), Latin text (Hershey), Chinese text (Make Me a Hanzi).

Every source yields a :class:`Glyph`: strokes in writing order, y axis up; :func:`fit_to_area`
places it, in metres, on a writing area.
"""

from planner.glyphs.glyph import FloatArray, Glyph, glyphs_equal
from planner.glyphs.hanzi import hanzi_characters
from planner.glyphs.hershey import DEFAULT_LATIN_FONT, hershey_font_names
from planner.glyphs.layout import fit_to_area
from planner.glyphs.strokes_json import MAX_POINTS, MAX_STROKES, parse_strokes_json
from planner.glyphs.text import MAX_TEXT_CHARS, has_glyph, text_glyph

__all__ = [
    "DEFAULT_LATIN_FONT",
    "MAX_POINTS",
    "MAX_STROKES",
    "MAX_TEXT_CHARS",
    "FloatArray",
    "Glyph",
    "fit_to_area",
    "glyphs_equal",
    "hanzi_characters",
    "has_glyph",
    "hershey_font_names",
    "parse_strokes_json",
    "text_glyph",
]

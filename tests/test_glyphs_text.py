"""Typed text in: Hershey Latin, Make Me a Hanzi Chinese, mixed lines, coverage."""

from __future__ import annotations

import numpy as np
import pytest

from planner.errors import PlannerError
from planner.glyphs import MAX_TEXT_CHARS, hanzi_characters, has_glyph, text_glyph


def gb2312_level1() -> list[str]:
    chars = []
    for hi in range(0xB0, 0xD8):
        for lo in range(0xA1, 0xFF):
            if (hi, lo) > (0xD7, 0xF9):
                break
            try:
                chars.append(bytes([hi, lo]).decode("gb2312"))
            except UnicodeDecodeError:
                continue  # undefined code point
    return chars


def test_gb2312_level1_is_fully_covered() -> None:
    level1 = gb2312_level1()
    assert len(level1) == 3755
    missing = [c for c in level1 if not has_glyph(c)]
    assert missing == []
    assert len(hanzi_characters()) >= 9000


@pytest.mark.parametrize(("char", "count"), [("一", 1), ("十", 2), ("马", 3), ("永", 5), ("光", 6)])
def test_known_stroke_counts(char: str, count: int) -> None:
    g = text_glyph(char)
    assert len(g.strokes) == count
    assert g.source == "hanzi-writer-data"
    assert g.units == "em"


def test_shi_stroke_order_and_direction() -> None:
    across, down = text_glyph("十").strokes
    # first the horizontal, drawn left to right; then the vertical, drawn top to bottom (y up)
    assert across[-1, 0] - across[0, 0] > 0.6
    assert abs(across[-1, 1] - across[0, 1]) < 0.1
    assert down[0, 1] - down[-1, 1] > 0.6
    assert abs(down[-1, 0] - down[0, 0]) < 0.1
    # the vertical crosses the horizontal near the middle of the cell
    assert 0.35 < down[0, 0] < 0.65


def test_chinese_cell_is_one_em() -> None:
    x_min, y_min, x_max, y_max = text_glyph("国").bounds()
    # 国's centrelines span most of its cell
    assert x_max - x_min > 0.5
    assert y_max - y_min > 0.5
    assert (x_min + x_max) / 2 == pytest.approx(0.5, abs=0.05)
    assert (y_min + y_max) / 2 == pytest.approx((900 - 124) / 2 / 1024, abs=0.05)


def test_every_character_lies_in_its_cell() -> None:
    for char in hanzi_characters():
        x_min, y_min, x_max, y_max = text_glyph(char).bounds()
        assert x_min >= 0.0 and x_max <= 1.0, char
        assert y_min >= -124 / 1024 and y_max <= 900 / 1024, char


def test_hershey_a_shape() -> None:
    g = text_glyph("A")
    assert g.source == "hershey:futural"
    assert len(g.strokes) == 3
    left, right, bar = g.strokes
    _, y_min, _, y_max = g.bounds()
    # both legs start at the apex: the top of the glyph, midway between the feet
    np.testing.assert_allclose(left[0], right[0])
    assert left[0, 1] == pytest.approx(y_max)
    assert left[-1, 1] == pytest.approx(y_min) == pytest.approx(0.0)
    assert left[-1, 0] < left[0, 0] < right[-1, 0]
    assert left[0, 0] == pytest.approx((left[-1, 0] + right[-1, 0]) / 2)
    # cap height 0.7 em; cross bar horizontal, between the feet and the apex
    assert y_max == pytest.approx(0.7)
    assert bar[0, 1] == bar[1, 1]
    assert 0.0 < bar[0, 1] < y_max


def test_word_is_laid_out_left_to_right() -> None:
    g = text_glyph("HI")
    h_right = max(s[:, 0].max() for s in g.strokes[:3])
    i_left = g.strokes[3][:, 0].min()
    assert len(g.strokes) == 4  # H: 3, I: 1
    assert i_left > h_right


def test_space_advances_without_ink() -> None:
    tight = text_glyph("II").bounds()
    spaced = text_glyph("I I").bounds()
    assert spaced[2] - spaced[0] > tight[2] - tight[0]
    assert len(text_glyph("I I").strokes) == 2


def test_mixed_latin_and_chinese_on_one_line() -> None:
    g = text_glyph("Hi马")
    assert g.source == "hershey:futural+hanzi-writer-data"
    assert g.label == "Hi马"
    assert len(g.strokes) == 3 + 2 + 3
    latin_right = max(s[:, 0].max() for s in g.strokes[:5])
    ma = g.strokes[5:]
    assert min(s[:, 0].min() for s in ma) > latin_right
    # same baseline, comparable heights
    assert max(s[:, 1].max() for s in ma) == pytest.approx(0.7, abs=0.15)


def test_unknown_character_names_character_and_index() -> None:
    with pytest.raises(PlannerError, match=r"'☃' \(U\+2603\) at index 2") as info:
        text_glyph("ab☃c")
    assert info.value.field == "text"


def test_newline_is_rejected() -> None:
    with pytest.raises(PlannerError, match="at index 1"):
        text_glyph("a\nb")


@pytest.mark.parametrize("text", ["", " ", "\u3000", "x" * (MAX_TEXT_CHARS + 1)])
def test_text_without_ink_or_too_long(text: str) -> None:
    with pytest.raises(PlannerError) as info:
        text_glyph(text)
    assert info.value.field == "text"


def test_unknown_font_is_named() -> None:
    with pytest.raises(PlannerError, match="nosuchfont") as info:
        text_glyph("A", latin_font="nosuchfont")
    assert info.value.field == "latin_font"


def test_other_hershey_font() -> None:
    assert text_glyph("A", latin_font="scripts").source == "hershey:scripts"


def test_has_glyph() -> None:
    assert has_glyph("a") and has_glyph(" ") and has_glyph("马") and has_glyph("\u3000")
    assert not has_glyph("☃") and not has_glyph("\n") and not has_glyph("ab") and not has_glyph("")


def test_hershey_fonts_and_chinese_store_share_no_character() -> None:
    """text_glyph looks a character up in the Chinese store first; that only gives the result of
    the Hershey font first because no built-in font has a character of the store (or U+3000)."""
    from planner.glyphs.hershey import _font, hershey_font_names

    chinese = hanzi_characters() | {"\u3000"}
    for name in hershey_font_names():
        glyphs, _ = _font(name)
        assert not chinese & set(glyphs), name

"""tui.safe_text: bus strings become one bounded line of plain, visible characters."""

from __future__ import annotations

import time
import unicodedata

from hypothesis import given
from hypothesis import strategies as st
from rich.console import Console

from tui.safe_text import clean, plain


def test_control_characters_are_shown_as_their_pictures() -> None:
    assert clean("\x1b[31mred\x00\r\n\t\x07\x7f") == "␛[31mred␀␍␊␉␇␡"
    assert clean("a\x85b\x9bc") == "a\ufffdb\ufffdc"  # C1 controls (NEL, CSI)


def test_bidi_and_other_invisible_formatting_is_replaced() -> None:
    overrides = "\u202a\u202b\u202c\u202d\u202e\u2066\u2067\u2068\u2069\u200e\u200f\u061c"
    assert clean(f"abc{overrides}def") == "abc" + "\ufffd" * len(overrides) + "def"
    assert clean("tag\U000e0041\ufeff\u2028\u2029") == "tag" + "\ufffd" * 4


def test_real_text_is_untouched() -> None:
    for text in (
        "永",
        "光 马",
        "[/x]",
        "$\\frac{1}{0}$",
        "a\u3000b",
        "👩\u200d💻",
        "é",
        "ای\u200cن",
    ):
        assert clean(text) == text


def test_long_strings_are_cut_first_and_cheaply() -> None:
    assert clean("W" * 10, 4) == "WWW…"
    assert clean("WWWW", 4) == "WWWW"
    start = time.perf_counter()
    assert clean("\x1b" * 10_000_000, 10) == "␛" * 9 + "…"
    assert time.perf_counter() - start < 0.5
    assert clean(12.5) == "12.5"


def test_plain_is_never_read_as_markup() -> None:
    console = Console(width=80, record=True, file=None, force_terminal=False)
    with console.capture() as capture:
        console.print(plain("[/x] [bold red]loud[/] [link=http://e.vil]x", style="bold"))
    assert capture.get().strip() == "[/x] [bold red]loud[/] [link=http://e.vil]x"


@given(st.text(), st.integers(1, 50))
def test_nothing_unsafe_survives(text: str, max_chars: int) -> None:
    shown = clean(text, max_chars)
    assert len(shown) <= max_chars
    for ch in shown:
        category = unicodedata.category(ch)
        assert category not in ("Cc", "Cs", "Zl", "Zp"), repr(ch)
        assert category != "Cf" or ch in "\u200c\u200d", repr(ch)

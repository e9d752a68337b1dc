"""The kiosk's words: one catalogue per language, the same keys in each, none left in the page.

Every visible string, label and placeholder of ``index.html`` comes from a catalogue through a
``data-i18n*`` attribute, and the scripts hold no sentence of their own: each key they name is
in the catalogues. (The pages in both languages are tried in tests/test_kiosk_browser.py.)
"""

from __future__ import annotations

import json
import re
from html.parser import HTMLParser
from pathlib import Path

import pytest

STATIC = Path(__file__).resolve().parents[1] / "kiosk" / "static"
LANGS = ("en", "zh-Hans")
SCRIPTS = ("i18n.js", "pictures.js", "widths.js", "status.js", "phrase.js", "kiosk.js")
WORDED_ATTRS = ("aria-label", "placeholder", "alt", "title")
CJK = re.compile(r"[\u3400-\u9fff]")
WORDS = re.compile(r"[A-Za-z]{2,}[,.!?:;'’]? [A-Za-z]{2,}")
"""Two words in a row: a sentence or a phrase someone reads."""
SCRIPT_LITERALS_NOT_SHOWN = {
    "use strict",  # a directive
    "touch screen",  # the drawing's ``device`` field for the planner, never shown
    "(prefers-reduced-motion: reduce)",  # a media query
}


def catalogue(lang: str) -> dict[str, str]:
    data = json.loads((STATIC / "i18n" / f"{lang}.json").read_text(encoding="utf-8"))
    assert isinstance(data, dict) and all(isinstance(v, str) and v for v in data.values())
    return data


def test_both_catalogues_have_the_same_keys_and_placeholders() -> None:
    en, zh = catalogue("en"), catalogue("zh-Hans")
    assert set(en) == set(zh)
    for key in en:
        names = set(re.findall(r"\{(\w+)\}", en[key]))
        assert names == set(re.findall(r"\{(\w+)\}", zh[key])), key
    assert zh["lang_name"] == "中文" and en["lang_name"] == "English"
    untranslated = [k for k in en if en[k] == zh[k] and not re.fullmatch(r"[{}\w ]*", en[k])]
    assert untranslated == []
    assert sum(bool(CJK.search(v)) for v in zh.values()) > 0.9 * len(zh)


class _Page(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.texts: list[str] = []
        self.attrs: list[tuple[str, str, str]] = []
        self.keys: set[str] = set()
        self._skip = 0

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self._skip += tag in ("script", "style")
        for name, value in attrs:
            if name in WORDED_ATTRS and value:
                self.attrs.append((tag, name, value))
            if name.startswith("data-i18n") and name != "data-i18n-args" and value:
                self.keys.add(value)

    def handle_endtag(self, tag: str) -> None:
        self._skip -= tag in ("script", "style")

    def handle_data(self, data: str) -> None:
        if not self._skip and data.strip() and data.strip() != "-":
            self.texts.append(data.strip())


def test_the_page_has_no_words_of_its_own() -> None:
    page = _Page()
    page.feed((STATIC / "index.html").read_text(encoding="utf-8"))
    assert page.texts == []  # every text comes from the catalogue
    assert page.attrs == []  # labels, placeholders and alternatives too
    assert page.keys and page.keys <= set(catalogue("en"))


def _literals(source: str) -> list[str]:
    source = re.sub(r"^\s*//.*$", "", source, flags=re.M)  # comments are not shown
    found = (m.group(2) for m in re.finditer(r"([\"'`])((?:\\.|(?!\1).)*)\1", source))
    return [text for text in found if re.sub(r"\$\{[^}]*\}", "", text).strip()]


@pytest.mark.parametrize("name", SCRIPTS)
def test_the_scripts_say_nothing_outside_the_catalogue(name: str) -> None:
    literals = _literals((STATIC / name).read_text(encoding="utf-8"))
    assert literals, "the literal scanner found nothing: it is broken"
    shown = [re.sub(r"\$\{[^}]*\}", "", s) for s in literals]  # template values are data
    sentences = [s for s in shown if WORDS.search(s) and s not in SCRIPT_LITERALS_NOT_SHOWN]
    assert sentences == []
    assert [s for s in literals if CJK.search(s)] == []
    keys = set(catalogue("en"))
    named = {s for s in literals if re.fullmatch(r"(st|err|acc|dur|pic|why|ph|phrase)_[a-z_]+", s)}
    assert named <= keys, named - keys


def test_the_scanner_would_catch_a_sentence() -> None:
    planted = 'say("Your character was sent.");\nconst ok = `${n} strokes`;'
    assert [s for s in _literals(planted) if WORDS.search(s)] == ["Your character was sent."]

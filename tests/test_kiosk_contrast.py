"""WCAG AA contrast of the kiosk page's colours, computed from kiosk.css itself.

Text needs 4.5:1 against its background; the drawing area's border and other parts of controls
need 3:1 (WCAG 2.1, 1.4.3 and 1.4.11), and so does the focus ring against what surrounds it
(WCAG 2.2, 2.4.13: the page behind the header's buttons, the panels, white fields). The ratio
follows the WCAG definition of relative luminance.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

CSS = (Path(__file__).resolve().parents[1] / "kiosk" / "static" / "kiosk.css").read_text()


def _variables() -> dict[str, str]:
    root = CSS[CSS.index(":root {") : CSS.index("}", CSS.index(":root {"))]
    return dict(re.findall(r"--([a-z-]+):\s*(#[0-9a-fA-F]{6})", root)) | {"white": "#ffffff"}


def _luminance(colour: str) -> float:
    def channel(c: int) -> float:
        s = c / 255.0
        return s / 12.92 if s <= 0.04045 else ((s + 0.055) / 1.055) ** 2.4

    r, g, b = (int(colour[i : i + 2], 16) for i in (1, 3, 5))
    return 0.2126 * channel(r) + 0.7152 * channel(g) + 0.0722 * channel(b)


def contrast(a: str, b: str) -> float:
    la, lb = sorted((_luminance(a), _luminance(b)), reverse=True)
    return (la + 0.05) / (lb + 0.05)


def test_contrast_formula_matches_known_values() -> None:
    assert contrast("#000000", "#ffffff") == pytest.approx(21.0)
    assert contrast("#767676", "#ffffff") == pytest.approx(4.54, abs=0.01)


@pytest.mark.parametrize(
    ("fore", "back", "minimum"),
    [
        ("white", "button", 4.5),  # main button text
        ("ink", "paper", 4.5),  # body text
        ("ink", "white", 4.5),  # secondary buttons, tabs
        ("muted", "paper", 4.5),  # facts, counts
        ("muted", "page", 4.5),  # the lead under the title
        ("hint", "white", 4.5),  # "Draw here"
        ("hint", "paper", 4.5),  # why a button is disabled
        ("bad", "bad-bg", 4.5),  # messages and "connection lost"
        ("border", "white", 3.0),  # drawing area, inputs, secondary buttons
        ("border", "paper", 3.0),
        ("air", "white", 3.0),  # dashed air moves of the path pictures
        ("focus", "page", 3.0),  # the focus ring: 4.00 (was #3a86ff: 2.95)
        ("focus", "paper", 3.0),  # 4.52
        ("focus", "white", 3.0),  # 4.71
    ],
)
def test_colour_pairs_meet_wcag_aa(fore: str, back: str, minimum: float) -> None:
    colours = _variables()
    assert contrast(colours[fore], colours[back]) >= minimum, (fore, back)


def test_the_rules_use_the_checked_colours() -> None:
    def rule(selector: str) -> str:
        return CSS[CSS.index(selector) : CSS.index("}", CSS.index(selector))]

    assert "background: var(--button)" in rule("button.primary {")
    assert "border: 2px solid var(--border)" in rule("#pad {")
    assert "color: var(--hint)" in rule(".pad-hint {")
    assert "color: var(--hint)" in rule(".hint {")
    js = (Path(__file__).resolve().parents[1] / "kiosk" / "static" / "pictures.js").read_text()
    assert _variables()["air"] in js and _variables()["ink"] in js  # the canvas uses them too
    assert "--line" not in CSS  # the old low-contrast border colour is gone
    outlines = re.findall(r"outline:\s*([^;]+);", CSS)
    assert "3px solid var(--focus)" in rule(":focus-visible {")
    assert outlines and all(o == "none" or "var(--focus)" in o for o in outlines), outlines

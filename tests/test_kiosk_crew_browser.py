"""The crew page in a real browser (Debian chromium through Playwright) on a running, secured
show (tests/test_crew_attacks.py's: real router with the generated access control, orchestrator,
agents, boards b1 and b2 waiting for a sheet; the kiosk with the public's and the crew's sessions).

The operator prints a pairing code (``skyquill crew SHOW --pair deck-1``); a phone enters it once;
b1 is listed, one tap, it is gone and the event log names the crew and the phone. The public's
page, in the same browser, cannot confirm anything.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest
from test_crew_attacks import CrewShow, crew_show
from test_kiosk_browser import CHROMIUM, SHOTS_DIR, UI_WAIT_MS, browser
from test_kiosk_browser_words import PHONE, open_page

from cli.main import main as skyquill
from cli.showrun import snapshot

pytestmark = [
    pytest.mark.browser,
    pytest.mark.slow,
    pytest.mark.multiprocess,
    pytest.mark.timeout(240),
    pytest.mark.skipif(not Path(CHROMIUM).exists(), reason="needs Debian chromium"),
]
__all__ = ["browser", "crew_show"]  # the fixtures, shared

CODE = re.compile(r"\b[A-Z2-9]{4}-[A-Z2-9]{4}\b")


def _pairing_code(show: CrewShow, capsys: pytest.CaptureFixture[str], name: str) -> str:
    assert skyquill(["crew", str(show.path), "--pair", name]) == 0
    found = CODE.search(capsys.readouterr().out)
    assert found is not None
    return found.group(0)


def _snapshot(show: CrewShow) -> Any:
    with show.run.client() as operator:
        return snapshot(operator, show.run.keys)


def test_a_crew_phone_pairs_and_confirms_a_fresh_sheet_with_one_tap(
    browser: Any, crew_show: CrewShow, capsys: pytest.CaptureFixture[str]
) -> None:
    code = _pairing_code(crew_show, capsys, "deck-1")
    page: Any = open_page(browser, crew_show.url + "crew", "zh-CN", PHONE)
    page.wait_for_selector("#pair:not([hidden])", timeout=UI_WAIT_MS)
    page.fill("#code", code.lower().replace("-", " "))  # as a phone's keyboard may type it
    page.tap("#pair-button")
    page.locator("#who").filter(has_text="deck-1").wait_for(timeout=UI_WAIT_MS)
    sheets = page.locator("#sheets li")
    sheets.filter(has_text="b2").wait_for(timeout=UI_WAIT_MS)
    b1 = sheets.filter(has_text="b1")
    assert b1.count() == 1 and "写字板" in b1.inner_text()
    assert page.evaluate("document.documentElement.scrollWidth") <= 320  # fits the phone
    SHOTS_DIR.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(SHOTS_DIR / "crew-phone.png"))

    b1.locator("button").tap()
    page.locator("#message").filter(has_text="已确认换纸").wait_for(timeout=UI_WAIT_MS)
    b1.wait_for(state="detached", timeout=UI_WAIT_MS)
    assert sheets.filter(has_text="b2").count() == 1  # only what was tapped
    snap = _snapshot(crew_show)
    assert "b1" not in snap.dirty_boards and "b2" in snap.dirty_boards
    said = [e.message for e in snap.events if e.kind == "operator"]
    assert "crew (deck-1): fresh_sheet b1" in said, said

    page.tap("button.lang[data-lang='en']")
    assert "Board" in sheets.filter(has_text="b2").inner_text()
    assert page.errors == []
    page.context.close()


def test_the_publics_page_cannot_confirm_for_the_crew(browser: Any, crew_show: CrewShow) -> None:
    page: Any = open_page(browser, crew_show.url, "en-GB", PHONE)
    status = page.evaluate(
        """async () => (await fetch("/crew/api/confirm", {method: "POST",
             headers: {"Content-Type": "application/json"},
             body: JSON.stringify({command: "fresh_sheet", target: "b2"})})).status"""
    )
    assert status == 401
    crew_page: Any = page.context.new_page()
    crew_page.goto(crew_show.url + "crew")
    crew_page.wait_for_selector("#pair:not([hidden])", timeout=UI_WAIT_MS)
    assert crew_page.locator("#work").is_hidden()
    assert "b2" in _snapshot(crew_show).dirty_boards
    page.context.close()

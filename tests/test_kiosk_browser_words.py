"""The kiosk in a real browser, in the visitor's language, showing the ink the drone left.

As tests/test_kiosk_browser.py: Debian chromium driven by Playwright, the real orchestrator in its
own process, the kiosk as its client; job states after ``queued`` are published the way the
orchestrator relays its agents' reports, here with the ink picture an agent makes
(:func:`vehicle_agent.written_ink.written_ink`). A second kiosk on the same show allows 5 s of
flight per character, to see a longer drawing refused before it is sent.
"""

from __future__ import annotations

import re
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import msgspec
import numpy as np
import pytest
from playwright.sync_api import TimeoutError as PlaywrightTimeout
from test_kiosk_browser import (
    CHROMIUM,
    REPO,
    SHOTS_DIR,
    SHOW_YAML,
    START_WAIT_S,
    UI_WAIT_MS,
    Show,
    _relay_until_shown,
    _wait_for_orchestrator,
    browser,
    touch_stroke,
)
from test_kiosk_support import done_metrics

from bus.keys import ShowKeys
from bus.session import ZenohSettings, free_tcp_endpoint, open_session
from kiosk.service import serving
from kiosk.settings import KioskSettings, settings_from_show
from showfile import load_show
from vehicle_agent.written_ink import ink_pixels, written_ink

pytestmark = [
    pytest.mark.browser,
    pytest.mark.slow,
    pytest.mark.multiprocess,
    pytest.mark.timeout(150),
    pytest.mark.skipif(not Path(CHROMIUM).exists(), reason="needs Debian chromium"),
]
__all__ = ["browser"]  # the browser fixture, shared

PHONE = {"viewport": {"width": 320, "height": 568}, "is_mobile": True, "has_touch": True}
TABLET = {"viewport": {"width": 1024, "height": 768}, "has_touch": True}
SHORT_FLIGHT_S = 5.0
HAN_TOUCHING_LATIN = re.compile(r"[\u3400-\u9fff][A-Za-z0-9]|[A-Za-z0-9][\u3400-\u9fff]")
"""A Han character run into a Latin letter or digit (Chinese sets a space between them)."""
PLAN_WAIT_MS = 60_000
"""Upper bound for planning a long drawing on a loaded machine; never a timing assertion."""


@dataclass
class Shows:
    show: Show
    short_url: str
    """A kiosk of the same show allowing :data:`SHORT_FLIGHT_S` per character."""
    settings: KioskSettings
    """The first kiosk's settings (to serve another one on the show)."""
    zenoh: ZenohSettings


@pytest.fixture(scope="module")
def shows(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Shows]:
    tmp = tmp_path_factory.mktemp("kiosk-words")
    path = tmp / "show.yaml"
    endpoint = free_tcp_endpoint()
    path.write_text(SHOW_YAML.format(endpoint=endpoint, tmp=tmp))
    loaded = load_show(path)
    keys = ShowKeys(loaded.show_id)
    log = (tmp / "orchestrator.log").open("wb")
    proc = subprocess.Popen(
        [sys.executable, "-m", "cli.main", "orchestrator", str(path), "--role", "router"],
        cwd=REPO, stdout=log, stderr=subprocess.STDOUT,
    )  # fmt: skip
    settings = settings_from_show(loaded, port=0)
    try:
        _wait_for_router(endpoint, proc)
        with open_session(loaded.zenoh, role="client", open_timeout_s=START_WAIT_S) as bus:
            _wait_for_orchestrator(bus, keys, proc)
            short = replace(settings, max_flight_s=SHORT_FLIGHT_S)
            with (
                serving(settings, loaded.zenoh, role="client") as server,
                serving(short, loaded.zenoh, role="client") as short_server,
            ):
                yield Shows(
                    Show(server.url, bus, keys, proc), short_server.url, settings, loaded.zenoh
                )
    finally:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(5)
        log.close()


def _wait_for_router(endpoint: str, proc: subprocess.Popen[bytes]) -> None:
    """Until the orchestrator's router listens (it starts slowly on a busy machine)."""
    host, port = endpoint.removeprefix("tcp/").rsplit(":", 1)
    deadline = time.monotonic() + 2 * START_WAIT_S
    while time.monotonic() < deadline:
        assert proc.poll() is None, "the orchestrator exited"
        try:
            socket.create_connection((host, int(port)), timeout=1.0).close()
            return
        except OSError:
            time.sleep(0.2)
    raise AssertionError(f"the orchestrator's router did not listen on {endpoint}")


def tap_until_sent(page: object, selector: str, request: str) -> None:
    """Tap ``selector`` until the page sends ``request``: headless Chromium drops some taps that
    follow synthetic touches (a visitor taps again too)."""
    sync_api = pytest.importorskip("playwright.sync_api")
    for _ in range(5):
        try:
            with page.expect_request(request, timeout=3_000):  # type: ignore[attr-defined]
                page.tap(selector)  # type: ignore[attr-defined]
            return
        except sync_api.TimeoutError:
            continue
    raise AssertionError(f"tapping {selector} never sent {request}")


def open_page(browser: object, url: str, locale: str, device: dict[str, object]) -> object:
    context = browser.new_context(locale=locale, **device)  # type: ignore[attr-defined]
    page = context.new_page()
    page.errors = []
    page.on("pageerror", lambda exc: page.errors.append(str(exc)))
    page.goto(url)
    page.wait_for_selector("body[data-ready='1']", timeout=UI_WAIT_MS)
    return page


def hand_in_typed(page: Any, text: str) -> str:
    """Type ``text``, preview it, hand it in; its job id (the API's: the page shows its code)."""
    page.tap("#tab-type")
    page.fill("#text", text)
    page.tap("#preview")
    page.wait_for_selector("#confirm:not([hidden])", timeout=UI_WAIT_MS)
    with page.expect_response("**/api/submit") as submitted:
        page.tap("#submit")
    page.wait_for_selector("#status:not([hidden])", timeout=UI_WAIT_MS)
    return str(submitted.value.json()["job_id"])


def lang(page: object) -> str:
    return str(page.evaluate("document.documentElement.lang"))  # type: ignore[attr-defined]


def fits(page: object, selector: str, height: int) -> bool:
    box = page.locator(selector).bounding_box()  # type: ignore[attr-defined]
    return bool(box["y"] + box["height"] <= height)


def test_chinese_from_the_browser_a_kept_switch_and_worded_refusals(
    browser: object, shows: Shows
) -> None:
    SHOTS_DIR.mkdir(parents=True, exist_ok=True)
    page = open_page(browser, shows.show.url, "zh-CN", PHONE)
    assert lang(page) == "zh-Hans"
    assert page.inner_text("h1") == "和无人机一起写字"
    assert page.inner_text("#preview-why") == "请先在方框里写一个字。"
    assert page.get_attribute("#pad", "aria-label").startswith("书写区")
    assert page.get_attribute("button.lang[data-lang='zh-Hans']", "aria-pressed") == "true"
    assert fits(page, "#preview", 568)  # the main button, in Chinese, on a small phone
    page.screenshot(path=str(SHOTS_DIR / "zh-320x568-start.png"))

    page.tap("#tab-type")
    page.fill("#text", "AB")
    page.tap("#preview")
    page.locator("#message").filter(has_text="请只输入一个字").wait_for(timeout=UI_WAIT_MS)
    page.fill("#text", "\U0001f600")
    page.tap("#preview")
    page.locator("#message").filter(has_text="无人机还不会写").wait_for(timeout=UI_WAIT_MS)
    page.screenshot(path=str(SHOTS_DIR / "zh-320x568-refused.png"))

    page.tap("button.lang[data-lang='en']")  # the switch rewords what is on screen now
    assert lang(page) == "en" and page.inner_text("h1") == "Write with the drones"
    assert "do not know how to write" in page.inner_text("#message")
    page.reload()
    page.wait_for_selector("body[data-ready='1']", timeout=UI_WAIT_MS)
    assert lang(page) == "en"  # kept in this browser
    assert page.errors == []
    page.context.close()

    tablet = open_page(browser, shows.show.url, "en-GB", TABLET)
    assert lang(tablet) == "en" and tablet.inner_text("#tab-draw") == "Draw"
    tablet.screenshot(path=str(SHOTS_DIR / "en-tablet-start.png"))
    tablet.click("button.lang[data-lang='zh-Hans']")
    assert lang(tablet) == "zh-Hans" and tablet.inner_text("#tab-draw") == "手写"
    assert fits(tablet, "#preview", 768)
    tablet.screenshot(path=str(SHOTS_DIR / "zh-tablet-start.png"))
    assert tablet.errors == []
    tablet.context.close()


def cross_ink() -> tuple[object, np.ndarray]:
    """The ink an agent would report for 十 written a little off: metrics with its picture."""
    t = np.linspace(0.0, 1.0, 120)[:, None]
    across = (1 - t) * [-0.4, 0.0] + t * [0.4, 0.01]
    down = (1 - t) * [0.01, 0.45] + t * [0.0, -0.45]
    tip = np.vstack([across, down])
    contact = np.ones(240, bool)
    contact[119:121] = False  # lifted between the strokes
    ink = written_ink(tip, np.full(240, 0.03), contact, (1.2, 1.2))
    return msgspec.structs.replace(done_metrics(), written=ink), ink_pixels(ink)


def canvas_dark(page: object, selector: str, fx: float, fy: float) -> bool:
    """Whether the canvas pixel at (fx, fy) of its size is ink-dark."""
    script = """([sel, fx, fy]) => {
        const c = document.querySelector(sel);
        const p = c.getContext("2d").getImageData(
            Math.floor(fx * c.width), Math.floor(fy * c.height), 1, 1).data;
        return p[3] > 128 && p[0] + p[1] + p[2] < 300;
    }"""
    return bool(page.evaluate(script, [selector, fx, fy]))  # type: ignore[attr-defined]


@pytest.mark.parametrize(
    ("locale", "device", "name"),
    [("zh-CN", PHONE, "zh-320x568"), ("en-GB", TABLET, "en-tablet")],
)
def test_the_finished_page_shows_the_ink_the_drone_left(
    browser: object, shows: Shows, locale: str, device: dict[str, object], name: str
) -> None:
    show = shows.show
    page = open_page(browser, show.url, locale, device)
    job_id = hand_in_typed(page, "十")
    assert show.command(command="approve", job_id=job_id).ok
    status = page.locator("#status-text")  # relayed until shown: a put beside a busy CI worker
    _relay_until_shown(show, status, job_id, "50%", "writing", vehicle_id="uav1", progress=0.5,
                       queue_position=None)  # fmt: skip
    assert page.is_hidden("#written-figure")  # only the plan while it is being written
    metrics, pixels = cross_ink()
    deadline = time.monotonic() + UI_WAIT_MS / 1000
    while True:  # relayed again, as in ``_relay_until_shown`` (a put beside a busy CI worker)
        show.relay(job_id, "done", vehicle_id="uav1", progress=1.0, metrics=metrics)
        try:
            page.wait_for_selector("#written-figure:not([hidden])", timeout=1000)
            break
        except PlaywrightTimeout:
            if time.monotonic() > deadline:
                raise

    canvas = page.locator("#written-canvas")
    assert int(canvas.get_attribute("data-inked")) == int(pixels.sum())  # every bit drawn
    assert canvas_dark(page, "#written-canvas", 0.5, 0.5)  # where the strokes cross
    assert canvas_dark(page, "#written-canvas", 0.25, 0.5)  # along the horizontal stroke
    assert not canvas_dark(page, "#written-canvas", 0.25, 0.25)  # no ink off the strokes
    plan, ink = page.locator("#result-canvas").bounding_box(), canvas.bounding_box()
    assert abs(plan["width"] - ink["width"]) < 2 and abs(plan["y"] - ink["y"]) < 2  # side by side
    facts = page.inner_text("#result-facts").replace("\xa0", " ")  # 1.2 cm: one unbroken line
    if locale == "zh-CN":
        assert "左起第 1 块板" in facts and "1.2 厘米" in facts and "80%" in facts
        assert "写好了" in page.inner_text("#status-text")
        assert "由 1 号无人机" in page.inner_text("#status-text")  # a space, as Chinese sets it
        assert not HAN_TOUCHING_LATIN.search(page.inner_text("#status-text") + facts)
    else:
        assert "board 1 from the left" in facts and "1.2 cm" in facts and "actually left" in facts
    page.locator("#result").scroll_into_view_if_needed()
    page.screenshot(path=str(SHOTS_DIR / f"{name}-done.png"), full_page=True)
    page.tap(f"button.lang[data-lang='{'en' if locale == 'zh-CN' else 'zh-Hans'}']")
    assert int(canvas.get_attribute("data-inked")) == int(pixels.sum())  # still drawn
    assert page.errors == []
    page.context.close()


@pytest.mark.parametrize("device", [PHONE, TABLET], ids=["phone", "tablet"])
def test_a_drawing_longer_than_the_flight_limit_is_refused_before_it_is_sent(
    browser: object, shows: Shows, device: dict[str, object]
) -> None:
    page = open_page(browser, shows.short_url, "en-GB", device)
    assert page.evaluate("fetch('/api/config').then(r => r.json())")["config"]["max_flight_s"] == 5
    sent: list[str] = []
    page.on("request", lambda r: sent.append(r.url) if "/api/submit" in r.url else None)
    jobs_before = len(shows.show.snapshot().jobs)
    for k in range(4):  # four long strokes: far more than 5 s of flight
        y = 0.15 + 0.2 * k
        touch_stroke(page, [(0.1, y), (0.9, y + 0.05), (0.1, y + 0.1)])
    tap_until_sent(page, "#preview", "**/api/preview")
    message = page.locator("#message")
    # the kiosk plans the whole drawing before it can say (slow on a busy machine)
    message.filter(has_text="5 seconds").wait_for(timeout=PLAN_WAIT_MS)
    # how long it would take against the show's limit, never "cannot fly this one"
    took = re.search(r"take the drone about (\d+) seconds", message.inner_text())
    assert took and int(took[1]) > SHORT_FLIGHT_S and page.is_hidden("#confirm")
    page.screenshot(path=str(SHOTS_DIR / f"too-long-{device['viewport']['width']}.png"))
    page.tap("button.lang[data-lang='zh-Hans']")
    assert f"大约需要 {took[1]} 秒" in message.inner_text() and "5 秒" in message.inner_text()
    assert sent == [] and len(shows.show.snapshot().jobs) == jobs_before  # nothing was sent
    assert page.errors == []
    page.context.close()


def test_a_paused_show_tells_the_visitor_and_the_character_keeps_its_place(
    browser: object, shows: Shows
) -> None:
    """The operator pauses the show: the visitor's page says so in their language (no start
    time it cannot keep), and words it again when the show goes on."""
    show = shows.show
    page = open_page(browser, show.url, "zh-CN", PHONE)
    job_id = hand_in_typed(page, "山")
    assert show.command(command="pause").ok
    try:
        assert show.command(command="approve", job_id=job_id).ok
        status = page.locator("#status-text")
        status.filter(has_text="表演暂时停下了").wait_for(timeout=UI_WAIT_MS)
        assert re.search(r"你仍排在第 \d+ 位", status.inner_text())  # its place, no start time
        page.tap("button.lang[data-lang='en']")
        assert "The show is paused for now" in status.inner_text()
        page.screenshot(path=str(SHOTS_DIR / "en-320x568-paused.png"))
        assert show.command(command="resume").ok
        status.filter(has_text="You are").wait_for(timeout=UI_WAIT_MS)  # next, or number N
        assert "paused" not in status.inner_text()
    finally:
        show.command(command="resume")
        show.command(command="cancel", job_id=job_id)
    assert page.errors == []
    page.context.close()

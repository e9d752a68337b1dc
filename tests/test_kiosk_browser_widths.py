"""Line width in a real browser: a finger pressing harder along a stroke on the kiosk's pad sends
growing widths, and the preview draws the planned ink wider where it is wider.

As tests/test_kiosk_browser.py: Debian chromium driven by Playwright; touches with a force go
through the DevTools protocol (``PointerEvent.pressure``). The kiosk previews for the hexarotor
on a wall (the real CasADi/IPOPT planner); no orchestrator is needed for a preview.
"""

from __future__ import annotations

import itertools
import re
from pathlib import Path
from typing import Any

import pytest
from test_kiosk_browser import CHROMIUM, SHOTS_DIR, UI_WAIT_MS, browser

from vehicles.registry import vehicle_kind

pytestmark = [
    pytest.mark.browser,
    pytest.mark.slow,
    pytest.mark.timeout(180),
    pytest.mark.skipif(not Path(CHROMIUM).exists(), reason="needs Debian chromium"),
]
__all__ = ["browser"]  # the browser fixture, shared

WALL = "hexarotor-sponge"
PLAN_WAIT_MS = 120_000
"""Upper bound for planning the preview on a loaded machine; never a timing assertion."""
INK_THICKNESS_JS = """(xs) => {
  const canvas = document.getElementById("preview-canvas");
  const { data, width, height } = canvas.getContext("2d").getImageData(
    0, 0, canvas.width, canvas.height);
  const rect = canvas.getBoundingClientRect();
  const dpr = canvas.width / rect.width;
  const scale = Math.min(rect.width / 0.5, rect.height / 0.5) * 0.92 * dpr;  // as pictures.js
  return xs.map((xm) => {
    const col = Math.round(width / 2 + xm * scale);
    let dark = 0;
    for (let row = 0; row < height; row += 1) {
      const i = 4 * (row * width + col);
      if (data[i + 3] > 128 && data[i] < 80 && data[i + 1] < 80) dark += 1;  // the ink, #14213d
    }
    return dark;
  });
}"""


def pressed_stroke(page: Any, points: list[tuple[float, float, float]]) -> None:
    """A finger through ``points`` (fractions of the pad, and the touch's force 0..1)."""
    box = page.locator("#pad").bounding_box()
    cdp = page.context.new_cdp_session(page)

    def touch(kind: str, fx: float, fy: float, force: float) -> None:
        at = {"x": box["x"] + fx * box["width"], "y": box["y"] + fy * box["height"]}
        cdp.send(
            "Input.dispatchTouchEvent", {"type": kind, "touchPoints": [{**at, "force": force}]}
        )

    touch("touchStart", *points[0])
    for (x0, y0, f0), (x1, y1, f1) in itertools.pairwise(points):
        for k in range(1, 11):
            s = k / 10
            touch("touchMove", x0 + (x1 - x0) * s, y0 + (y1 - y0) * s, f0 + (f1 - f0) * s)
    cdp.send("Input.dispatchTouchEvent", {"type": "touchEnd", "touchPoints": []})
    cdp.detach()


def test_pressing_harder_draws_wider_in_the_preview(browser: Any, wall_kiosk: str) -> None:
    context = browser.new_context(
        viewport={"width": 390, "height": 844}, device_scale_factor=2, is_mobile=True,
        has_touch=True,
    )  # fmt: skip
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    sent: list[Any] = []
    page.on("request", lambda r: sent.append(r.post_data_json) if "/api/preview" in r.url else None)
    page.goto(wall_kiosk)
    page.wait_for_selector("body[data-ready='1']", timeout=UI_WAIT_MS)

    # one horizontal stroke, the finger pressing from light to hard
    pressed_stroke(page, [(0.2, 0.5, 0.1), (0.5, 0.5, 0.55), (0.8, 0.5, 1.0)])
    page.click("#preview")
    page.wait_for_selector("#confirm:not([hidden])", timeout=PLAN_WAIT_MS)
    page.wait_for_selector("#preview-canvas[data-drawn='1']", timeout=UI_WAIT_MS)

    (body,) = sent
    (stroke,) = body["strokes"]["strokes"]
    widths = [p["w"] for p in stroke]
    wall = vehicle_kind(WALL)
    low, high = wall.width_range_m(wall.settings(None, None)) or (0.0, 0.0)
    assert all(low - 1e-9 <= w <= high + 1e-9 for w in widths)
    assert widths[-1] - widths[0] > 0.7 * (high - low)  # from the pressure, not constant
    assert all(b >= a - 1e-9 for a, b in itertools.pairwise(widths))

    # the drawing spans the writing area less its margin: x = -0.2 .. 0.2 m; a quarter and
    # three quarters along, the ink is about 8 and 12 mm wide
    left, right = page.evaluate(INK_THICKNESS_JS, [-0.1, 0.1])
    assert left > 0 and right > left * 1.25, (left, right)
    said = re.search(r"(\d+\.\d) to (\d+\.\d) mm", page.inner_text("#preview-widths"))
    assert said is not None and 5.0 <= float(said[1]) < float(said[2]) <= 14.0
    assert "wall" in page.inner_text("#legend-ink")
    SHOTS_DIR.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(SHOTS_DIR / "phone-wall-widths.png"))
    assert errors == []
    context.close()


def test_without_pressure_a_faster_line_is_thinner(browser: Any, wall_kiosk: str) -> None:
    """The page's own rule (kiosk/static/widths.js) on a mouse's points: pressure 0.5 all along,
    10 px apart, first every 0.1 s (100 px/s) then every 0.01 s (1000 px/s)."""
    page = browser.new_page()
    page.goto(wall_kiosk)
    page.wait_for_selector("body[data-ready='1']", timeout=UI_WAIT_MS)
    times = [0.1 * i for i in range(10)] + [0.9 + 0.01 * i for i in range(1, 11)]
    stroke = [[10.0 * i, 50.0, t, 0.5] for i, t in enumerate(times)]
    widths, pressed = page.evaluate(
        """([stroke, range]) => [
            window.SkyquillWidths.strokeWidths(stroke, range),
            window.SkyquillWidths.hasPressure(stroke),
        ]""",
        [stroke, [0.005, 0.014]],
    )
    assert pressed is False
    slow, fast = widths[3], widths[-4]
    assert slow == pytest.approx(0.014 - 0.009 * 100 / 1200, abs=1e-4)
    assert fast == pytest.approx(0.014 - 0.009 * 1000 / 1200, abs=1e-4)
    # a pen's pressure wins over the speed
    stroke[5][3] = 0.9
    assert page.evaluate("s => window.SkyquillWidths.hasPressure(s)", stroke) is True
    page.close()

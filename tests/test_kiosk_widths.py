"""Line width in the kiosk: a board whose kind writes with a width (the hexarotor's sponge on a
wall) gets the pen's range in ``/api/config``, and its preview gives the planned width at each
point of the path; a width the pen cannot write is refused with a code. Over HTTP against a real
kiosk (uvicorn in a thread) planning with the real hexarotor planner (CasADi/IPOPT)."""

from __future__ import annotations

import json
import urllib.error
import urllib.request
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from kiosk.settings import KioskSettings, settings_from_show
from showfile import load_show
from vehicles.hexarotor_sponge.pen import PenCurve
from vehicles.registry import vehicle_kind

pytestmark = [pytest.mark.slow, pytest.mark.timeout(240)]

WALL = "hexarotor-sponge"
PLAN_WAIT_S = 120.0
"""Upper bound for one IPOPT preview on a loaded machine; never a timing assertion."""


def call(base_url: str, path: str, body: dict[str, Any] | None = None) -> tuple[int, Any]:
    data = None if body is None else json.dumps(body).encode()
    request = urllib.request.Request(base_url.rstrip("/") + path, data=data)
    if data is not None:
        request.add_header("Content-Type", "application/json")
    try:
        with urllib.request.urlopen(request, timeout=PLAN_WAIT_S) as reply:
            return reply.status, json.loads(reply.read())
    except urllib.error.HTTPError as err:
        with err:
            return err.code, json.loads(err.read())


def line(widths_m: list[float]) -> dict[str, Any]:
    """One horizontal stroke drawn left to right in pad pixels, a width per point."""
    points = [
        {"x": 20.0 + 10.0 * i, "y": 100.0 + 0.5 * (i % 2), "t": 0.05 * i, "w": w}
        for i, w in enumerate(widths_m)
    ]
    return {"strokes": {"units": "px", "y_axis": "down", "strokes": [points]}}


def pen_down_widths(preview: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """x in [m] and planned width in [m] of the path's pen-down points."""
    down = np.array([[p[0], p[3]] for p in preview["path"] if p[2]])
    return down[:, 0], down[:, 1]


def test_each_kind_says_the_widths_it_draws() -> None:
    wall = vehicle_kind(WALL)
    low, high = wall.width_range_m(wall.settings(None, None))
    pen = PenCurve()
    assert (low, high) == pytest.approx((pen.width_min_m, pen.width_max_m), abs=1e-9)
    assert (low, high) == pytest.approx((0.005, 0.014))
    for one_width in ("quadrotor-brush", "omni-wheel"):
        kind = vehicle_kind(one_width)
        assert kind.width_range_m(kind.settings(None, None)) is None


def test_a_show_previews_for_the_kind_on_its_first_board() -> None:
    show = load_show(Path(__file__).resolve().parents[1] / "shows" / "solo.yaml")
    brush = settings_from_show(show)
    assert [k.kind.name for k in brush.kinds()] == ["quadrotor-brush"]
    assert brush.width_range_m is None
    first = show.boards[0].id
    vehicles = [
        v.model_copy(update={"kind": WALL}) if v.board == first else v for v in show.vehicles
    ]
    wall = settings_from_show(show.model_copy(update={"vehicles": vehicles}))
    assert [k.kind.name for k in wall.kinds()] == [WALL]
    assert wall.width_range_m == pytest.approx((0.005, 0.014))  # the show file's pen
    # each kind's settings are its vehicle's own, the brush's like any other kind's
    assert type(wall.preview_kinds[0].settings).__name__ == "WallSettings"
    assert type(brush.preview_kinds[0].settings).__name__ == "QuadrotorSettings"


def test_config_gives_the_pen_range(wall_kiosk: str) -> None:
    status, body = call(wall_kiosk, "/api/config")
    assert status == 200
    assert body["config"]["width_range_m"] == pytest.approx([0.005, 0.014])


def test_a_drawing_wider_to_the_right_is_planned_wider_to_the_right(wall_kiosk: str) -> None:
    widths = list(np.round(np.linspace(0.005, 0.014, 21), 5))
    status, body = call(wall_kiosk, "/api/preview", line(widths))
    assert status == 200, body
    preview = body["preview"]
    assert preview["kind"] == WALL and preview["widths"] is True
    assert preview["widths_clamped"] == 0
    x, w = pen_down_widths(preview)
    # away from the ends (where the sponge is pressed on and lifted off), the planned width
    # follows the drawn one: about 7 mm a quarter along, about 12 mm three quarters along
    left = w[(x > -0.12) & (x < -0.08)]
    right = w[(x > 0.08) & (x < 0.12)]
    assert left.size and right.size
    assert np.median(left) == pytest.approx(0.00725, abs=1.5e-3)
    assert np.median(right) == pytest.approx(0.01175, abs=1.5e-3)


def test_a_width_the_pen_cannot_write_is_refused_with_its_code(wall_kiosk: str) -> None:
    widths = [0.009] * 10 + [0.03] + [0.009] * 10
    status, body = call(wall_kiosk, "/api/preview", line(widths))
    assert status == 422
    error = body["error"]
    assert error["code"] == "bad_width" and error["stroke_index"] == 0
    assert "pen" in error["message"] and "Traceback" not in error["message"]


def test_typed_text_gets_the_default_width_profile(wall_kiosk: str) -> None:
    """Typed text carries no width: the kind's profile swells in the middle of a stroke."""
    status, body = call(wall_kiosk, "/api/preview", {"text": "I"})
    assert status == 200, body
    assert body["preview"]["widths"] is True
    _, w = pen_down_widths(body["preview"])
    assert w.max() <= 0.014 + 1e-6
    n = len(w)
    middle, ends = w[n // 3 : 2 * n // 3], np.r_[w[: n // 10], w[-(n // 10) :]]
    assert middle.min() >= 0.005 - 1e-6  # inside the pen's range where the line is laid
    assert np.median(middle) > np.median(ends) + 0.002


def test_a_brush_board_previews_without_widths() -> None:
    from kiosk.limits import Submission
    from kiosk.preview import plan_preview

    settings = KioskSettings(show_id="t")
    preview = plan_preview(Submission(text="L", strokes=None, label="L"), settings)
    assert preview["widths"] is False and preview["kind"] == "quadrotor-brush"
    assert {len(p) for p in preview["path"]} == {3}

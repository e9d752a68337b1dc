"""Every kind's job picture is readable at a glance: 1280 px wide in the compact mode and small
enough for a job's 100 kB, the glyph's own characters in its title (spelt U+XXXX, visibly, where
no font draws them), nothing cut off, no two texts overlapping, the whole writing in view."""

from __future__ import annotations

from itertools import combinations
from pathlib import Path

import numpy as np
import pytest
from matplotlib.figure import Figure
from matplotlib.text import Text
from matplotlib.transforms import Bbox
from PIL import Image

import vehicles.picture as picture
from planner.glyphs import text_glyph
from showfile import load_show
from vehicle_agent.job_files import COMPACT_PICTURE_COLOURS, COMPACT_PICTURE_DPI
from vehicles.jobs import job_setup
from vehicles.kind import FlownWriting

SHOWS = Path(__file__).resolve().parent.parent / "shows"
CASES = [
    ("solo.yaml", "uav1", "永"),  # its top dot at the edge of the writing
    ("flying-calligrapher.yaml", "calligrapher", "人"),
    ("ground-writers.yaml", "ground1", "永"),
]
COMPACT_PICTURE_MAX_BYTES = 60_000
"""Room for the picture in a compact job of 100 kB beside its flight and reference (a 20 s
brush job's ``flight.npz`` is ~30 kB)."""


def _flown_as_planned(plan: object, width_m: float) -> FlownWriting:
    """``plan`` flown exactly, recorded at every other tick (a live run's own clock), without
    the batch simulation's logs (a live trace has no wheel slip)."""
    s = plan.samples  # type: ignore[attr-defined]
    force = plan.force_n  # type: ignore[attr-defined]
    return FlownWriting(
        t_s=s.t_s[::2],
        reference_m_enu=s.position_m_enu[::2],
        writing_point_m_enu=s.position_m_enu[::2],
        pen_down=s.pen_down[::2],
        ink_width_m=np.where(s.pen_down[::2], width_m, 0.0),
        base_m_enu=s.position_m_enu[::2],
        force_n=None if force is None else force[::2],
        extra={"velocity_mps_enu": s.velocity_mps_enu[::2]},
    )


def _texts(figure: Figure) -> list[tuple[str, Bbox]]:
    """Every text drawn: titles, labels, legends, and the tick labels inside the view."""
    figure.canvas.draw()
    renderer = figure.canvas.get_renderer()  # type: ignore[attr-defined]
    ticks_drawn, ticks_all = set(), set()
    for ax in figure.axes:
        for axis in (ax.xaxis, ax.yaxis):
            lo, hi = sorted(axis.get_view_interval())
            for tick in axis.get_major_ticks() + axis.get_minor_ticks():
                labels = {id(tick.label1), id(tick.label2)}
                ticks_all |= labels
                if lo - 1e-9 * (hi - lo) <= tick.get_loc() <= hi + 1e-9 * (hi - lo):
                    ticks_drawn |= labels
    found = []
    for text in figure.findobj(Text):
        assert isinstance(text, Text)
        if id(text) in ticks_all and id(text) not in ticks_drawn:
            continue
        if text.get_visible() and text.get_text().strip():
            found.append((text.get_text(), text.get_window_extent(renderer)))
    return found


@pytest.mark.parametrize(("show_name", "vehicle_id", "glyph"), CASES)
def test_a_kinds_picture_is_wide_small_and_nothing_is_cut_off_or_overlaps(
    tmp_path: Path, show_name: str, vehicle_id: str, glyph: str
) -> None:
    js = job_setup(load_show(SHOWS / show_name), vehicle_id)
    plan = js.plan(text_glyph(glyph)).plan
    flown = _flown_as_planned(plan, 0.01)
    figure = js.kind.report(plan, flown, js.settings, "永: job j1 on a vehicle, attempt 1")
    path = tmp_path / "report.png"
    picture.save_png(figure, path, dpi=COMPACT_PICTURE_DPI, colours=COMPACT_PICTURE_COLOURS)
    with Image.open(path) as image:
        assert image.width >= 1200 and image.mode == "P"
    assert path.stat().st_size < COMPACT_PICTURE_MAX_BYTES
    texts = _texts(figure)
    assert any(text.startswith("永") for text, _ in texts)  # the character, not U+6C38
    page = figure.bbox
    for text, box in texts:
        inside = page.x0 <= box.x0 <= box.x1 <= page.x1 and page.y0 <= box.y0 <= box.y1 <= page.y1
        assert inside, f"{text!r} is cut off"
        assert box.height >= 12.0, f"{text!r} is {box.height:.0f} px high"  # 10 pt at 100 dpi
    for (a, box_a), (b, box_b) in combinations(texts, 2):
        assert not box_a.overlaps(box_b), f"{a!r} overlaps {b!r}"
    written = js.surface.to_surface(flown.writing_point_m_enu[flown.pen_down])
    board = figure.axes[0] if show_name != "solo.yaml" else figure.axes[6]
    (x0, x1), (y0, y1) = board.get_xlim(), board.get_ylim()
    assert x0 < written[:, 0].min() and written[:, 0].max() < x1  # 永's dot in view
    assert y0 < written[:, 1].min() and written[:, 1].max() < y1


def test_titles_keep_the_glyphs_characters_and_spell_what_no_font_draws(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    if not picture._installed_cjk():
        pytest.skip("no CJK font installed (scripts/system-deps.sh installs fonts-noto-cjk)")
    assert picture.plain_title("永 by quadrotor-brush") == "永 by quadrotor-brush"
    assert picture.plain_heading("鬱\u202e\nsecond\nthird") == "鬱U+202E\nsecond"
    monkeypatch.setattr(picture, "_drawable_codepoints", lambda: frozenset(range(0x20, 0x7F)))
    assert picture.plain_title("永 by quadrotor-brush") == "U+6C38 by quadrotor-brush"

"""A kind's report figure as PNG (the live agent's ``report.png``, ``skyquill fly --report``):
one size and type scale for every kind, titles drawn literally in the glyph's own characters, and
a palette PNG small enough for a compact job directory."""

from __future__ import annotations

import os
from functools import lru_cache
from pathlib import Path
from typing import Any

from matplotlib import font_manager
from matplotlib.artist import Artist
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import Collection
from matplotlib.figure import Figure
from matplotlib.ft2font import FT2Font
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.text import Text

WIDTH_IN = 12.8
"""Width in [in] of every kind's report figure: 1280 px at :data:`DPI`."""
DPI = 100.0
"""The figures' own resolution in [dots/in] (``report.png`` of ``skyquill fly --report``)."""
TITLE_PT = 13.0
"""Size in [pt] of a figure's heading; at 100 dpi 18 px, panel titles a point less."""
LABEL_PT = 11.0
"""Size in [pt] of axis labels and legends (15 px at 100 dpi)."""
TICK_PT = 10.0
"""Size in [pt] of tick labels (14 px at 100 dpi; 36 dpi, used before, drew them 5 px high)."""

CJK_FONTS = ("Noto Sans CJK SC", "Noto Serif CJK SC")
"""Fonts that draw Chinese labels (Debian's fonts-noto-cjk, ``scripts/system-deps.sh``), tried
after each text's own font."""
TITLE_MAX_CHARS = 160
"""Longest title line drawn, in characters (before spelling): a label is data of any length."""
TITLE_MAX_LINES = 2
"""Lines of a heading drawn (the job's line, the pace line of a paced job); more are dropped."""


def report_figure(height_in: float) -> Figure:
    """An empty report figure, :data:`WIDTH_IN` wide, laid out by matplotlib's constrained
    layout (nothing cut off, no overlapping labels), drawn by Agg (never pyplot: headless, in
    any thread)."""
    figure = Figure(figsize=(WIDTH_IN, height_in), dpi=DPI, layout="constrained")
    FigureCanvasAgg(figure)
    return figure


def legend_below(figure: Figure) -> None:
    """One legend of every labelled artist of the figure's panels, in a row below them (none
    inside a panel, where it would hide the writing)."""
    entries: dict[str, Artist] = {}
    for ax in figure.axes:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            entries.setdefault(label, handle)
    if entries:
        figure.legend(list(entries.values()), list(entries), loc="outside lower center",
                      ncol=len(entries), fontsize=LABEL_PT, frameon=False)  # fmt: skip


def plain_title(text: str) -> str:
    """``text`` as a title that is drawn literally: cut to ``TITLE_MAX_CHARS`` with an ellipsis,
    one line, and every character that is not printable (control codes, bidirectional
    overrides, line breaks) or that no installed font draws (Chinese without a CJK font) spelt
    as U+XXXX, visibly. The caller draws it with ``parse_math=False``, so ``$...$`` stays text
    rather than matplotlib mathtext."""
    if len(text) > TITLE_MAX_CHARS:
        text = text[: TITLE_MAX_CHARS - 3] + "..."
    drawable = _drawable_codepoints()
    return "".join(
        ch if ch.isprintable() and ord(ch) in drawable else f"U+{ord(ch):04X}" for ch in text
    )


def plain_heading(text: str) -> str:
    """``text``'s first :data:`TITLE_MAX_LINES` lines, each a :func:`plain_title`."""
    return "\n".join(plain_title(line) for line in text.splitlines()[:TITLE_MAX_LINES])


def save_png(
    figure: Figure, path: Path, *, dpi: float | None = None, colours: int | None = None
) -> None:
    """Write the figure as PNG atomically (a reader never sees half a file), at ``dpi`` (None:
    the figure's own); ``colours``: as a palette image of that many colours, its lines, areas
    and patches drawn without anti-aliasing (text with), None: full colour. Chinese characters
    in its texts (a job's label) are drawn with a CJK font where one is installed."""
    _fall_back_to_cjk(figure)
    if (engine := figure.get_layout_engine()) is not None:
        engine.execute(figure)  # once: savefig would lay out again for a dry run, then draw
        figure.set_layout_engine("none")
    partial = path.with_name(f".{path.name}.partial")
    if colours is None:
        figure.savefig(str(partial), format="png", dpi="figure" if dpi is None else dpi)
    else:
        _palette_image(figure, dpi, colours).save(partial, format="png", optimize=True)
    os.replace(partial, path)


def _palette_image(figure: Figure, dpi: float | None, colours: int) -> Any:
    """The figure drawn at ``dpi`` (None: its own) as a PIL palette image of ``colours``
    colours, its lines, areas and patches not anti-aliased (a pure colour each, kept by the
    palette), read from the canvas (no PNG encoded and decoded in between)."""
    from PIL import Image

    for artist in figure.findobj(lambda a: isinstance(a, (Line2D, Collection, Patch))):
        artist.set_antialiased(False)  # type: ignore[attr-defined]
    if dpi is not None:
        figure.set_dpi(dpi)
    canvas = FigureCanvasAgg(figure)
    canvas.draw()  # type: ignore[no-untyped-call]
    renderer = canvas.get_renderer()  # type: ignore[no-untyped-call]
    size = (int(renderer.width), int(renderer.height))
    rgba = canvas.buffer_rgba()  # type: ignore[no-untyped-call]
    rgb = Image.frombuffer("RGBA", size, rgba, "raw", "RGBA", 0, 1).convert("RGB")
    return rgb.quantize(colours, method=Image.Quantize.FASTOCTREE, dither=Image.Dither.NONE)


def _installed_cjk() -> list[str]:
    installed = {font.name for font in font_manager.fontManager.ttflist}
    return [name for name in CJK_FONTS if name in installed]


@lru_cache(maxsize=1)
def _drawable_codepoints() -> frozenset[int]:
    """Code points that the default font or an installed CJK font has a glyph for."""
    families = [font_manager.FontProperties()]
    families += [font_manager.FontProperties(family=name) for name in _installed_cjk()]
    points: set[int] = set()
    for properties in families:
        path = font_manager.findfont(properties, fallback_to_default=False)
        points.update(FT2Font(path).get_charmap())
    return frozenset(points)


def _fall_back_to_cjk(figure: Figure) -> None:
    cjk = _installed_cjk()
    if not cjk:
        return
    for text in figure.findobj(Text):
        assert isinstance(text, Text)
        text.set_fontfamily([*text.get_fontfamily(), *cjk])

"""A kind's report figure as PNG (the live agent's ``report.png``, ``skyquill fly --report``)."""

from __future__ import annotations

import os
from pathlib import Path

from matplotlib import font_manager
from matplotlib.figure import Figure
from matplotlib.text import Text

CJK_FONTS = ("Noto Sans CJK SC", "Noto Serif CJK SC")
"""Fonts that draw Chinese labels (Debian's fonts-noto-cjk), tried after each text's own font."""


def save_png(figure: Figure, path: Path, *, dpi: float | None = None) -> None:
    """Write the figure as PNG atomically (a reader never sees half a file), at ``dpi`` (None:
    the figure's own); Chinese characters in its texts (a job's label) are drawn with a CJK font
    where one is installed."""
    _fall_back_to_cjk(figure)
    partial = path.with_name(f".{path.name}.partial")
    figure.savefig(str(partial), format="png", dpi="figure" if dpi is None else dpi)
    os.replace(partial, path)


def _fall_back_to_cjk(figure: Figure) -> None:
    installed = {font.name for font in font_manager.fontManager.ttflist}
    cjk = [name for name in CJK_FONTS if name in installed]
    if not cjk:
        return
    for text in figure.findobj(Text):
        assert isinstance(text, Text)
        text.set_fontfamily([*text.get_fontfamily(), *cjk])

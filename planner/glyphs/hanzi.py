"""Chinese characters: stroke centrelines in stroke order, from Make Me a Hanzi's medians.

The store ``data/hanzi_medians.bin`` is derived from the npm package hanzi-writer-data by
``scripts/build_hanzi_data.py`` (Arphic Public License; see ``data/LICENSE-hanzi-writer-data.txt``).
Its index is read on first use; each character's record is read when that character is asked for
(:mod:`planner.glyphs.hanzi_store`).
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np

from planner.errors import PlannerError
from planner.glyphs.glyph import FloatArray
from planner.glyphs.hanzi_store import HanziStore

HANZI_SOURCE = "hanzi-writer-data"
"""The ``Glyph.source`` of a Chinese character."""
GRID = 1024.0
"""Size of the data's square grid; one CJK character cell is 1 em = GRID units."""
STORE_PATH = Path(__file__).parent / "data" / "hanzi_medians.bin"
"""The committed stroke store."""


@functools.cache
def _store() -> HanziStore:
    return HanziStore(STORE_PATH)


def hanzi_characters() -> frozenset[str]:
    """Every character that has stroke data."""
    return _store().characters()


def has_hanzi(char: str) -> bool:
    """True when ``char`` has stroke data."""
    return char in _store()


@functools.lru_cache(maxsize=256)  # bounded: a long show must not keep every character it saw
def hanzi_strokes_em(char: str) -> tuple[FloatArray, ...]:
    """Centrelines of ``char`` in stroke order, in em, y up, baseline at y = 0, cell x in [0, 1].

    The cell spans y from -124/1024 to 900/1024 em. Arrays are read-only.
    """
    points = _store().strokes(char)
    if points is None:
        raise PlannerError(f"no stroke data for {char!r} (U+{ord(char):04X})", field="text")
    strokes = []
    for stroke in points:
        scaled = np.asarray(stroke, dtype=np.float64) / GRID
        scaled.flags.writeable = False
        strokes.append(scaled)
    return tuple(strokes)

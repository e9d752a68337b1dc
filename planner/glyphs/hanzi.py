"""Chinese characters: stroke centrelines in stroke order, from Make Me a Hanzi's medians.

The data file ``data/hanzi_medians.json.gz`` is derived from the npm package hanzi-writer-data by
``scripts/build_hanzi_data.py`` (Arphic Public License; see ``data/LICENSE-hanzi-writer-data.txt``).
It is read once, on first use.
"""

from __future__ import annotations

import functools
import gzip
import json
from importlib import resources

import numpy as np

from planner.errors import PlannerError
from planner.glyphs.glyph import FloatArray

HANZI_SOURCE = "hanzi-writer-data"
"""The ``Glyph.source`` of a Chinese character."""
GRID = 1024.0
"""Size of the data's square grid; one CJK character cell is 1 em = GRID units."""
_DATA_FILE = "hanzi_medians.json.gz"
_FORMAT = "skyquill-hanzi-medians"


@functools.cache
def _encoded_medians() -> dict[str, list[list[int]]]:
    raw = resources.files("planner.glyphs.data").joinpath(_DATA_FILE).read_bytes()
    doc = json.loads(gzip.decompress(raw))
    if doc.get("format") != _FORMAT or doc.get("version") != 1:
        raise PlannerError(f"{_DATA_FILE}: unexpected format {doc.get('format')!r}")
    chars: dict[str, list[list[int]]] = doc["chars"]
    return chars


def hanzi_characters() -> frozenset[str]:
    """Every character that has stroke data."""
    return frozenset(_encoded_medians())


def has_hanzi(char: str) -> bool:
    """True when ``char`` has stroke data."""
    return char in _encoded_medians()


@functools.lru_cache(maxsize=2048)
def hanzi_strokes_em(char: str) -> tuple[FloatArray, ...]:
    """Centrelines of ``char`` in stroke order, in em, y up, baseline at y = 0, cell x in [0, 1].

    The cell spans y from -124/1024 to 900/1024 em. Arrays are read-only.
    """
    encoded = _encoded_medians().get(char)
    if encoded is None:
        raise PlannerError(f"no stroke data for {char!r} (U+{ord(char):04X})", field="text")
    strokes = []
    offset = np.zeros(2)
    for flat in encoded:
        steps = np.asarray(flat, dtype=np.float64).reshape(-1, 2)
        points = offset + np.cumsum(steps, axis=0)
        offset = points[-1]
        scaled = points / GRID
        scaled.flags.writeable = False
        strokes.append(scaled)
    return tuple(strokes)
